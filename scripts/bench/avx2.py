"""The environment that makes pathcl run AVX2 code on an AVX-512 machine (the benchmarks' --avx2, where no AVX2
machine is at hand): Debian's PoCL is built with one kernel library per instruction set and takes its -target-cpu
from the library it uses, which POCL_KERNELLIB_NAME chooses (avx2: -target-cpu haswell); it ignores
POCL_LLVM_CPU_NAME, which PoCL builds without those variants read instead. pathcl then takes 8 lanes and the
8-wide BVH, as it does on an AVX2 CPU (its device name still says avx512, so they are set here). The code and
the vector width are an AVX2 machine's; the caches, clock and memory are this machine's."""

AVX2_ENV = {"POCL_KERNELLIB_NAME": "avx2", "POCL_LLVM_CPU_NAME": "haswell", "PATHCL_LANES": "8",
            "PATHCL_BVH_WIDTH": "8"}

# Mitsuba 3's LLVM variants on AVX2 code (scripts/bench/peer_runners.py --avx2): Dr.Jit's jit_llvm_set_target
# (libdrjit-core), Haswell without AVX-512 and 8-wide vectors, as Dr.Jit picks on an AVX2 CPU.
DRJIT_AVX2_TARGET = ("haswell", "-avx512f,-avx512vl,-avx512bw,-avx512dq,-avx512cd,+avx,+avx2,+fma,+f16c,+bmi,+bmi2,"
                     "+lzcnt,+popcnt", 8)
