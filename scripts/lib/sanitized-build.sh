# Sourced by scripts/sanitize and scripts/fuzz: installs clang with libFuzzer and the sanitizer runtimes, and
# configures build-asan/, the one instrumented build of both. Every source is compiled once with ASan and UBSan
# (every report fatal), the libraries also with the fuzzer's coverage instrumentation (-DPATHCL_FUZZ=ON; the
# top-level CMakeLists.txt says which): the tests link them (the coverage hooks are the sanitizer runtime's
# no-ops there) and so do the fuzzers (fuzz/CMakeLists.txt). -O1 (the command lines and a few other cold
# files at -O0: CMakeLists.txt says which) and NDEBUG as in Release, but CGAL's checks
# on in the mesh clean-up (CMakeLists.txt), libstdc++'s own checks on (_GLIBCXX_ASSERTIONS), line tables for
# reports; the tests' own code at -O0 (tests/CMakeLists.txt).
# clang rather than the Release build's gcc: a second compiler's view of the same code, and 0.6 times gcc's
# compile time for these flags (scene_load_test.cpp: 11 s against 19 s), which the suite's time needs.
source scripts/lib/packages.sh
install_packages clang-14 libclang-rt-14-dev
# A build-asan/ of the gcc days (or of any other flags) is configured again from scratch.
sanitized_flags="-fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer -D_GLIBCXX_ASSERTIONS"
if [ -f build-asan/CMakeCache.txt ] && ! grep -qF "CMAKE_CXX_FLAGS:STRING=$sanitized_flags" build-asan/CMakeCache.txt; then
  rm -rf build-asan
fi
if [ ! -f build-asan/build.ninja ]; then
  cmake -S . -B build-asan -G Ninja -DCMAKE_CXX_COMPILER=clang++-14 -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -gline-tables-only -DNDEBUG" -DCMAKE_CXX_FLAGS="$sanitized_flags" \
    -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=address,undefined" -DPATHCL_SANITIZED=ON -DPATHCL_FUZZ=ON \
    -DPATHCL_TEST_CODE_OPTIMIZATION=-O0 >/dev/null
fi
