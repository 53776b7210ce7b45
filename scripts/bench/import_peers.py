"""scripts/bench/import-peers: imported scenes rendered by pathcl against Mitsuba 3 (see that script)."""
import argparse
import glob
import json
import os
import re
import subprocess
import sys
import time

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
BUILD = os.environ.get("PATHCL_BUILD", os.path.join(ROOT, "build"))
PATHCL = os.path.join(ROOT, BUILD, "pathcl") if not os.path.isabs(BUILD) else os.path.join(BUILD, "pathcl")
OUT = os.path.join(ROOT, "bench", "out", "import-peers")

# Each case: the file pathcl renders and its reference, a Mitsuba file of the same scene that Mitsuba 3
# renders here ("mitsuba") or an image another renderer made ("exr"); "defaults" overrides the Mitsuba
# files' <default> values (resolution, depth) in copies beside them. {MITSUBA_DATA}: mitsuba-data's
# checkout; {BITTERLI}: Bitterli's scenes as converted for Mitsuba 3 and pbrt-v4 (github.com/gonsolo/bitterli);
# {TESTS}: tests/scenes.
CASES = {
    "mitsuba-data-cbox": {"pathcl": "{MITSUBA_DATA}/scenes/cbox/cbox.xml", "mitsuba": "{MITSUBA_DATA}/scenes/cbox/cbox.xml"},
    "mitsuba-data-cbox-rgb": {"pathcl": "{MITSUBA_DATA}/scenes/cbox/cbox-rgb.xml",
                              "mitsuba": "{MITSUBA_DATA}/scenes/cbox/cbox-rgb.xml"},
    "tests-mitsuba-cbox": {"pathcl": "{TESTS}/mitsuba/cbox.xml", "mitsuba": "{TESTS}/mitsuba/cbox.xml"},
    "tests-pbrt-cornell-box": {"pathcl": "{TESTS}/pbrt/cornell-box.pbrt", "mitsuba": "{TESTS}/pbrt/cornell-box-twin.xml"},
    "bitterli-cornell-box-xml": {"pathcl": "{BITTERLI}/cornell-box/mitsuba/scene_v3.xml",
                                 "mitsuba": "{BITTERLI}/cornell-box/mitsuba/scene_v3.xml",
                                 "defaults": {"resx": "256", "resy": "256"}},
    # The pbrt-v4 file (64 x 64, maxdepth 4 as that repository leaves it) against the Mitsuba file of the
    # same scene at pbrt's depth (Mitsuba counts the emitter's vertex: 5).
    "bitterli-cornell-box-pbrt": {"pathcl": "{BITTERLI}/cornell-box/pbrt/scene-v4.pbrt",
                                  "mitsuba": "{BITTERLI}/cornell-box/mitsuba/scene_v3.xml",
                                  "defaults": {"resx": "64", "resy": "64", "max_depth": "5"}},
    # Mitsuba's gallery (mitsuba-data's docs/scenes), which leaves $spp to the command line ("define").
    "gallery-plastic": {"pathcl": "{MITSUBA_DATA}/docs/scenes/bsdf_plastic_default.xml",
                        "mitsuba": "{MITSUBA_DATA}/docs/scenes/bsdf_plastic_default.xml", "define": {"spp": "16"}},
    "gallery-conductor-gold": {"pathcl": "{MITSUBA_DATA}/docs/scenes/bsdf_conductor_gold.xml",
                               "mitsuba": "{MITSUBA_DATA}/docs/scenes/bsdf_conductor_gold.xml", "define": {"spp": "16"}},
    "gallery-dielectric-glass": {"pathcl": "{MITSUBA_DATA}/docs/scenes/bsdf_dielectric_glass.xml",
                                 "mitsuba": "{MITSUBA_DATA}/docs/scenes/bsdf_dielectric_glass.xml", "define": {"spp": "16"}},
    "gallery-thindielectric": {"pathcl": "{MITSUBA_DATA}/docs/scenes/bsdf_thindielectric_glass.xml",
                               "mitsuba": "{MITSUBA_DATA}/docs/scenes/bsdf_thindielectric_glass.xml",
                               "define": {"spp": "16"}},
    # Veach's multiple-importance-sampling scene in Mitsuba's form (include/veach_mis.xml).
    "gallery-veach-mis": {"pathcl": "{MITSUBA_DATA}/docs/scenes/integrator_direct_both.xml",
                          "mitsuba": "{MITSUBA_DATA}/docs/scenes/integrator_direct_both.xml"},
    "gallery-bunny": {"pathcl": "{MITSUBA_DATA}/docs/scenes/shape_ply_bunny.xml",
                      "mitsuba": "{MITSUBA_DATA}/docs/scenes/shape_ply_bunny.xml", "define": {"spp": "16"}},
    # Veach's multiple-importance-sampling scene as pbrt-v4 file (maxdepth 3) against Tungsten's render.
    "bitterli-veach-mis-pbrt": {"pathcl": "{BITTERLI}/veach-mis/pbrt/scene-v4.pbrt",
                                "exr": "{BITTERLI}/veach-mis/pbrt/TungstenRender.exr"},
}

MITSUBA_RENDER = r"""
import sys, time, json
import numpy as np, OpenEXR, mitsuba as mi
mi.set_variant(sys.argv[1])
import drjit as dr
t = time.time()
scene = mi.load_file(sys.argv[2], **json.loads(sys.argv[6]))
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


def with_defaults(path, defaults):
    """The Mitsuba file with its <default> values replaced, written beside it (its relative paths hold);
    the file itself when there is nothing to replace."""
    if not defaults or not path.endswith(".xml"):
        return path
    text = open(path).read()
    for key, value in defaults.items():
        text, n = re.subn(r'(<default\s+name="%s"\s+value=")[^"]*(")' % re.escape(key), r"\g<1>%s\g<2>" % value, text)
        if n == 0:
            raise RuntimeError("%s has no <default name=\"%s\">" % (path, key))
    copy = path[:-4] + ".import-peers.xml"
    with open(copy, "w") as f:
        f.write(text)
    return copy


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
    ap.add_argument("--bitterli", default=os.path.join(ROOT, "build", "bitterli"))
    ap.add_argument("--json", default=os.path.join(ROOT, "bench", "out", "import-peers.json"), help="results file")
    args = ap.parse_args()
    data, bitterli = os.path.abspath(args.mitsuba_data), os.path.abspath(args.bitterli)
    names = args.cases.split(",")
    if any(n.startswith("mitsuba-data") for n in names) and not os.path.isdir(os.path.join(data, "scenes")):
        run(["git", "clone", "-q", "--depth", "1", "https://github.com/mitsuba-renderer/mitsuba-data", data])
    if any(n.startswith("bitterli") for n in names) and not os.path.isdir(os.path.join(bitterli, "cornell-box")):
        run(["git", "clone", "-q", "--depth", "1", "https://github.com/gonsolo/bitterli", bitterli])
    os.makedirs(OUT, exist_ok=True)
    env, variant = mitsuba_env()
    results = []
    for name in names:
        case = {k: (v.format(MITSUBA_DATA=data, BITTERLI=bitterli, TESTS=os.path.join(ROOT, "tests", "scenes"))
                    if isinstance(v, str) else v) for k, v in CASES[name].items()}
        ours = with_defaults(case["pathcl"], case.get("defaults", {}))
        test = os.path.join(OUT, name + "-pathcl.exr")
        if "mitsuba" in case:
            theirs = with_defaults(case["mitsuba"], case.get("defaults", {}))
            ref = os.path.join(OUT, name + "-mitsuba.exr")
            m = json.loads(run([sys.executable, "-c", MITSUBA_RENDER, variant, theirs, str(args.spp), str(args.seed), ref,
                                json.dumps(case.get("define", {}))], env=env).stdout.strip().splitlines()[-1])
            reference = {"renderer": "Mitsuba %s %s" % (m["version"], variant), "file": theirs, "seconds": m["seconds"]}
        else:
            theirs = ref = case["exr"]
            reference = {"renderer": "the image beside the scene file", "file": theirs}
        t = time.time()
        defines = [w for k, v in case.get("define", {}).items() for w in ("-D", "%s=%s" % (k, v))]
        r = run([PATHCL, "render", ours, "--spp", str(args.spp), "--seed", str(args.seed), "-o", test, "-q"] + defines)
        pathcl_seconds = time.time() - t
        warnings = [l for l in run([PATHCL, "info", ours] + defines).stdout.splitlines() if l.startswith("warning:")]
        c = json.loads(run([PATHCL, "compare", ref, test, "--json"]).stdout)
        ratio = [t_ / r_ if r_ else float("nan") for t_, r_ in zip(c["mean_test"], c["mean_reference"])]
        results.append({"case": name, "pathcl_file": os.path.relpath(ours, ROOT), "reference": reference,
                        "spp": args.spp, "pathcl_seconds": pathcl_seconds,
                        "mean_reference": c["mean_reference"], "mean_pathcl": c["mean_test"], "mean_ratio": ratio,
                        "relmse": c["relmse"], "within_3_percent": all(abs(x - 1) <= 0.03 for x in ratio),
                        "warnings": sorted(set(warnings))})
        print("%-26s means pathcl/reference %s  relMSE %.4g  %s" % (
            name, " ".join("%.4f" % x for x in ratio), c["relmse"], "ok" if results[-1]["within_3_percent"] else "OFF"),
            flush=True)
    with open(args.json, "w") as f:
        json.dump({"spp": args.spp, "cases": results}, f, indent=1)


if __name__ == "__main__":
    main()
