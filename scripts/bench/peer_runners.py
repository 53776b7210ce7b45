"""Runs one peer render in this process and prints `PATHCL_BENCH {json}` lines (called by peers.py in a
subprocess, so that each renderer has the machine to itself and a crash is reported, not fatal).

  peer_runners.py mitsuba VARIANT SCENE.xml --spp-series 1,4,16 --seed S --out PATTERN [--timeout T] [--avx2]
  peer_runners.py luxcore ENGINE DIR --spp-series 1,4,16 --seed S --out PATTERN [--time T]

PATTERN gets {spp} replaced. Mitsuba renders each sample count separately (the scene is loaded once);
LuxCore renders once and saves the film when its pass count reaches each sample count (a snapshot of a
progressive render, as pathcl's --convergence), or once after --time seconds.
"""
import argparse
import json
import os
import sys
import time

T0 = time.time()


def emit(**kw):
    print("PATHCL_BENCH " + json.dumps(kw), flush=True)


def write_exr(path, rgb):
    import numpy as np
    import OpenEXR
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    OpenEXR.File(header, {c: np.ascontiguousarray(rgb[..., k], dtype=np.float32) for k, c in enumerate("RGB")}).write(path)


def drjit_target(dr, cpu, features, width):
    """Dr.Jit's LLVM backend compiles for cpu with features and width-wide vectors from here on (its C++
    jit_llvm_set_target; the backend must have started, so a first kernel runs before)."""
    import ctypes
    dr.eval(dr.llvm.Float(0) + 1)
    core = ctypes.CDLL(os.path.join(os.path.dirname(dr.__file__), "libdrjit-core.so"))
    set_target = getattr(core, "_Z19jit_llvm_set_targetPKcS0_j")
    set_target.argtypes = [ctypes.c_char_p, ctypes.c_char_p, ctypes.c_uint32]
    set_target(cpu.encode(), features.encode(), width)


def mitsuba(args):
    import mitsuba as mi
    mi.set_variant(args.variant)
    import drjit as dr
    if args.avx2:
        from avx2 import DRJIT_AVX2_TARGET
        drjit_target(dr, *DRJIT_AVX2_TARGET)
    params = {"seed": str(args.seed)}
    if args.timeout:
        params["timeout"] = str(args.timeout)
    scene = mi.load_file(args.scene, **params)
    setup = time.time() - T0
    series = [int(x) for x in args.spp_series.split(",")]
    for spp in series:
        t = time.time()
        image = mi.render(scene, spp=spp, seed=args.seed)
        dr.eval(image)
        image = image.numpy() if hasattr(image, "numpy") else image
        seconds = time.time() - t
        out = args.out.replace("{spp}", str(spp))
        write_exr(out, image)
        emit(spp=spp, render_seconds=seconds, setup_seconds=setup, out=out, version=mi.__version__)


def luxcore(args):
    # numpy before pyluxcore, and no OpenEXR module in this process: with pyluxcore 2.11 importing numpy
    # after it, or the OpenEXR module beside it, aborts ("free(): invalid pointer"). Snapshots are .npy.
    import numpy as np
    import pyluxcore
    pyluxcore.Init()
    os.chdir(args.scene)
    props = pyluxcore.Properties("render.cfg")
    series = [int(x) for x in args.spp_series.split(",")]
    props.Set(pyluxcore.Property("renderengine.type", args.variant))
    props.Set(pyluxcore.Property("renderengine.seed", args.seed))
    props.Set(pyluxcore.Property("batch.haltspp", 0 if args.time else max(series)))
    props.Set(pyluxcore.Property("batch.halttime", args.time or 0))
    config = pyluxcore.RenderConfig(props)
    session = pyluxcore.RenderSession(config)
    width, height = (props.Get(k).GetInt() for k in ("film.width", "film.height"))
    buf = np.zeros((height, width, 3), dtype=np.float32)
    session.Start()
    setup = time.time() - T0
    t = time.time()
    pending = list(series) if not args.time else []

    def save(spp):
        session.GetFilm().GetOutputFloat(pyluxcore.FilmOutputType.RGB, buf)
        out = args.out.replace("{spp}", str(spp)).replace(".exr", ".npy")
        np.save(out, buf[::-1].copy())  # the film buffer's row 0 is the bottom
        return out

    while True:
        time.sleep(0.02)
        session.UpdateStats()
        passes = session.GetStats().Get("stats.renderengine.pass").GetInt()
        while pending and passes >= pending[0]:
            seconds = time.time() - t
            out = save(pending[0])
            emit(spp=passes, target_spp=pending.pop(0), render_seconds=seconds, setup_seconds=setup, out=out,
                 version=pyluxcore.Version())
        if session.HasDone() or (not args.time and not pending):
            break
    if args.time:
        seconds = time.time() - t
        emit(spp=passes, render_seconds=seconds, setup_seconds=setup, out=save(0), version=pyluxcore.Version())
    session.Stop()


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("peer", choices=["mitsuba", "luxcore"])
    ap.add_argument("variant")
    ap.add_argument("scene")
    ap.add_argument("--spp-series", default="1")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--out", required=True)
    ap.add_argument("--timeout", type=float, default=0, help="Mitsuba: integrator timeout in seconds")
    ap.add_argument("--time", type=float, default=0, help="LuxCore: halt time in seconds")
    ap.add_argument("--avx2", action="store_true", help="Mitsuba's LLVM variants: AVX2 code (scripts/bench/avx2.py)")
    args = ap.parse_args()
    (mitsuba if args.peer == "mitsuba" else luxcore)(args)


if __name__ == "__main__":
    sys.exit(main())
