"""scripts/bench/import-peers: imported scenes rendered by pathcl against Mitsuba 3 (see that script)."""
import argparse
import glob
import json
import os
import subprocess
import sys
import time

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
BUILD = os.environ.get("PATHCL_BUILD", os.path.join(ROOT, "build"))
PATHCL = os.path.join(ROOT, BUILD, "pathcl") if not os.path.isabs(BUILD) else os.path.join(BUILD, "pathcl")
OUT = os.path.join(ROOT, "bench", "out", "import-peers")

# name: (the file pathcl renders, the Mitsuba file of the same scene). MITSUBA_DATA is mitsuba-data's
# checkout, TESTS tests/scenes.
CASES = {
    "mitsuba-data-cbox": ("{MITSUBA_DATA}/scenes/cbox/cbox.xml", "{MITSUBA_DATA}/scenes/cbox/cbox.xml"),
    "mitsuba-data-cbox-rgb": ("{MITSUBA_DATA}/scenes/cbox/cbox-rgb.xml", "{MITSUBA_DATA}/scenes/cbox/cbox-rgb.xml"),
    "tests-mitsuba-cbox": ("{TESTS}/mitsuba/cbox.xml", "{TESTS}/mitsuba/cbox.xml"),
    "tests-pbrt-cornell-box": ("{TESTS}/pbrt/cornell-box.pbrt", "{TESTS}/pbrt/cornell-box-twin.xml"),
}

MITSUBA_RENDER = r"""
import sys, time, json
import numpy as np, OpenEXR, mitsuba as mi
mi.set_variant(sys.argv[1])
import drjit as dr
t = time.time()
scene = mi.load_file(sys.argv[2])
image = mi.render(scene, spp=int(sys.argv[3]), seed=int(sys.argv[4]))
dr.eval(image)
rgb = np.asarray(image)[..., :3]
OpenEXR.File({"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage},
             {c: np.ascontiguousarray(rgb[..., k], dtype=np.float32) for k, c in enumerate("RGB")}).write(sys.argv[5])
print(json.dumps({"seconds": time.time() - t, "version": mi.__version__}))
"""


def mitsuba_env():
    env = dict(os.environ)
    found = sorted(glob.glob("/usr/lib/*/libLLVM.so.19*") + glob.glob("/usr/lib/llvm-19/lib/libLLVM*.so*"))
    if found:
        env["DRJIT_LIBLLVM_PATH"] = found[0]  # Dr.Jit with the system's LLVM 15 aborts (scripts/bench/peers.py)
    return env, ("llvm_ad_rgb" if found else "scalar_rgb")


def run(cmd, **kw):
    r = subprocess.run(cmd, capture_output=True, text=True, **kw)
    if r.returncode != 0:
        raise RuntimeError("%s failed (%d):\n%s%s" % (" ".join(cmd), r.returncode, r.stdout[-2000:], r.stderr[-4000:]))
    return r


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--spp", type=int, default=1024)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--cases", default=",".join(CASES))
    ap.add_argument("--mitsuba-data", default=os.path.join(ROOT, "build", "mitsuba-data"))
    args = ap.parse_args()
    data = os.path.abspath(args.mitsuba_data)
    names = args.cases.split(",")
    if any(n.startswith("mitsuba-data") for n in names) and not os.path.isdir(os.path.join(data, "scenes")):
        run(["git", "clone", "-q", "--depth", "1", "https://github.com/mitsuba-renderer/mitsuba-data", data])
    os.makedirs(OUT, exist_ok=True)
    env, variant = mitsuba_env()
    results = []
    for name in names:
        ours, theirs = (p.format(MITSUBA_DATA=data, TESTS=os.path.join(ROOT, "tests", "scenes")) for p in CASES[name])
        ref = os.path.join(OUT, name + "-mitsuba.exr")
        test = os.path.join(OUT, name + "-pathcl.exr")
        m = json.loads(run([sys.executable, "-c", MITSUBA_RENDER, variant, theirs, str(args.spp), str(args.seed), ref],
                           env=env).stdout.strip().splitlines()[-1])
        t = time.time()
        r = run([PATHCL, "render", ours, "--spp", str(args.spp), "--seed", str(args.seed), "-o", test, "-q"])
        pathcl_seconds = time.time() - t
        warnings = [l for l in (r.stderr or "").splitlines() if l.startswith("warning:")]
        info = run([PATHCL, "info", ours]).stdout
        warnings += [l for l in info.splitlines() if l.startswith("warning:")]
        c = json.loads(run([PATHCL, "compare", ref, test, "--json"]).stdout)
        ratio = [t_ / r_ if r_ else float("nan") for t_, r_ in zip(c["mean_test"], c["mean_reference"])]
        results.append({"case": name, "pathcl_file": os.path.relpath(ours, ROOT) if ours.startswith(ROOT) else ours,
                        "mitsuba_file": os.path.relpath(theirs, ROOT) if theirs.startswith(ROOT) else theirs,
                        "spp": args.spp, "mitsuba_variant": variant, "mitsuba_version": m["version"],
                        "mitsuba_seconds": m["seconds"], "pathcl_seconds": pathcl_seconds,
                        "mean_mitsuba": c["mean_reference"], "mean_pathcl": c["mean_test"], "mean_ratio": ratio,
                        "relmse": c["relmse"], "within_3_percent": all(abs(x - 1) <= 0.03 for x in ratio),
                        "warnings": sorted(set(warnings))})
        print("%-24s means pathcl/Mitsuba %s  relMSE %.4g  %s" % (
            name, " ".join("%.4f" % x for x in ratio), c["relmse"], "ok" if results[-1]["within_3_percent"] else "OFF"),
            flush=True)
    with open(os.path.join(ROOT, "bench", "out", "import-peers.json"), "w") as f:
        json.dump({"spp": args.spp, "cases": results}, f, indent=1)


if __name__ == "__main__":
    main()
