#!/usr/bin/env python3
"""Samples per second of the path integrator at 1, 8 and 16 lanes against Mitsuba 3's llvm_ad_rgb (issue 15;
a benchmark, not a test), side by side on this machine: the Cornell box (scenes/cornell-official.json,
256 x 256), glass and metal (scenes/glass-metal.json) and the benchmark terrain (scripts/make-bench-scene),
each renderer with the independent sampler, the scene's depth and spp. Rounds alternate every
configuration (A B C D A B C D ...); figures are medians over the rounds. pathcl's samples/s is its
render time's (--stats samples_per_second, kernel builds from the cache); Mitsuba's is the second of two
mi.render calls in one process (the first compiles its kernel), both through scripts/bench/peer_runners.py's
timing. Mitsuba's `independent` sampler is what the issue's bar names; the peer benchmark gives each its
best sampler for time to an error (scripts/bench/peers).
With --builds it also builds each scene's path program at each W cold (fresh PoCL and pathcl kernel
caches) and from the cache (kernel_build_ms of --stats), and reads the stack frames of the compiled
kernel (`sub $N, %rsp` of each function of PoCL's shared object, objdump from Debian's binutils): PoCL
reports 1024 bytes of private memory for every kernel, so the frames are the measure of a work item's
private memory there (the largest frame, and the sum of all as a bound on the deepest call chain).
Usage: scripts/bench/lanes [--rounds N] [--scenes cornell,glass-metal,terrain] [--lanes 1,8,16] [--builds] [--avx2]
--avx2: both renderers run AVX2 code on an AVX-512 machine (scripts/bench/avx2.py), 8-wide vectors each.
Writes bench/results/lanes/<date>T<hhmm>.json and prints a table.
"""
import argparse
import datetime
import glob
import json
import os
import platform
import re
import shutil
import statistics
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, HERE)
import export_mitsuba  # noqa: E402
from avx2 import AVX2_ENV  # noqa: E402
import scene_model  # noqa: E402

BUILD = os.path.join(ROOT, os.environ.get("PATHCL_BUILD", "build"))
PATHCL = os.path.join(BUILD, "pathcl")
WORK = os.path.join(ROOT, "build", "bench-lanes")
AVX2 = False  # --avx2 (main sets it)
SCENES = {"cornell": os.path.join(ROOT, "scenes", "cornell-official.json"),
          "glass-metal": os.path.join(ROOT, "scenes", "glass-metal.json")}


def run(cmd, env=None):
    r = subprocess.run(cmd, capture_output=True, text=True, env=env)
    if r.returncode:
        sys.exit("%s: exit %d\n%s" % (" ".join(cmd), r.returncode, (r.stderr + r.stdout)[-2000:]))
    return r.stdout


def scene_path(name):
    if name in SCENES:
        if name == "glass-metal" and not os.path.exists(scene_model.ICOSPHERE_MESH):
            scene_model.write_icosphere_obj()
        return SCENES[name]
    if name == "terrain":
        path = os.path.join(WORK, "terrain.json")
        if not os.path.exists(path):
            run([sys.executable, os.path.join(ROOT, "scripts", "make-bench-scene"), WORK])
        return path
    sys.exit("unknown scene %s (cornell, glass-metal, terrain)" % name)


def pathcl_env():
    return dict(os.environ, **AVX2_ENV) if AVX2 else None


def mitsuba_env():
    env = dict(os.environ)
    found = sorted(glob.glob("/usr/lib/*/libLLVM.so.19*") + glob.glob("/usr/lib/llvm-19/lib/libLLVM*.so*"))
    if found:  # Dr.Jit aborts with Debian's default LLVM 15 (scripts/bench/peers.py)
        env["DRJIT_LIBLLVM_PATH"] = found[0]
    return env


def pathcl_samples(scene, lanes, spp):
    stats = os.path.join(WORK, "stats.json")
    run([PATHCL, "render", scene, "-o", os.path.join(WORK, "pathcl.exr"), "--quiet", "--sampler", "independent",
         "--lanes", str(lanes), "--spp", str(spp), "--stats", stats], pathcl_env())
    with open(stats) as f:
        return json.load(f)["samples_per_second"]


def mitsuba_samples(xml, variant, spp, pixels):
    out = run([sys.executable, os.path.join(HERE, "peer_runners.py"), "mitsuba", variant, xml, "--spp-series",
               "%d,%d" % (spp, spp), "--seed", "1", "--out", os.path.join(WORK, "mitsuba-{spp}.exr")]
              + (["--avx2"] if AVX2 else []), mitsuba_env())
    lines = [json.loads(l[len("PATHCL_BENCH "):]) for l in out.splitlines() if l.startswith("PATHCL_BENCH ")]
    return pixels * spp / lines[-1]["render_seconds"], lines[-1]["version"]


def builds(scene, lanes):
    """Cold and cached kernel build (ms) of the scene's path program at `lanes`, and the stack frames of its
    compiled kernel on PoCL: (largest frame, its function, sum of all frames)."""
    tmp = tempfile.mkdtemp(prefix="pathcl-builds-")
    env = dict(pathcl_env() or os.environ, POCL_CACHE_DIR=os.path.join(tmp, "pocl"),
               PATHCL_KERNEL_CACHE=os.path.join(tmp, "pathcl"))
    stats = os.path.join(tmp, "stats.json")
    times = []
    for _ in range(2):
        run([PATHCL, "render", scene, "-o", os.path.join(tmp, "out.exr"), "--quiet", "--lanes", str(lanes), "--spp", "1",
             "--stats", stats], env)
        with open(stats) as f:
            times.append(json.load(f)["kernel_build_ms"])
    frames = {}
    for so in glob.glob(os.path.join(tmp, "pocl", "**", "render_pass.so"), recursive=True):
        name = None
        for line in run(["objdump", "-d", "--no-show-raw-insn", so]).splitlines():
            m = re.match(r"^[0-9a-f]+ <(.+)>:$", line)
            if m:
                name = m.group(1)
                continue
            m = re.search(r"\bsub\s+\$0x([0-9a-f]+),%rsp", line)
            if m and name and name not in frames:
                frames[name] = int(m.group(1), 16)
    shutil.rmtree(tmp, ignore_errors=True)
    largest = max(frames.items(), key=lambda kv: kv[1]) if frames else ("", 0)
    return {"cold_ms": times[0], "cached_ms": times[1], "largest_frame_bytes": largest[1],
            "largest_frame_function": largest[0], "all_frames_bytes": sum(frames.values())}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--scenes", default="cornell,glass-metal,terrain")
    ap.add_argument("--lanes", default="1,8,16")
    ap.add_argument("--mitsuba", default="llvm_ad_rgb", help="Mitsuba variants, comma-separated ('' for none)")
    ap.add_argument("--builds", action="store_true", help="also cold and cached build times and stack frames per W")
    ap.add_argument("--avx2", action="store_true", help="AVX2 code for both renderers (scripts/bench/avx2.py)")
    args = ap.parse_args()
    global AVX2
    AVX2 = args.avx2
    os.makedirs(WORK, exist_ok=True)
    lanes = [int(x) for x in args.lanes.split(",") if x]
    variants = [v for v in args.mitsuba.split(",") if v]
    result = {"date": datetime.datetime.now().isoformat(timespec="seconds"), "host": platform.node(),
              "cpu": platform.processor() or platform.machine(), "rounds": args.rounds, "avx2": args.avx2,
              "pathcl": run([PATHCL, "--version"]).splitlines()[0], "scenes": {}}
    for name in [s for s in args.scenes.split(",") if s]:
        scene = scene_path(name)
        with open(scene) as f:
            j = json.load(f)
        spp = int(j.get("render", {}).get("spp", 16))
        pixels = j["camera"]["width"] * j["camera"]["height"]
        dump = os.path.join(WORK, name + ".obj")
        scene_model.dump_scene_obj(PATHCL, scene, dump)
        xml = export_mitsuba.export(scene_model.load(scene, dump), os.path.join(WORK, name + "-mitsuba"),
                                    sampler="independent")
        for l in lanes:  # kernel builds into the cache before the timed rounds
            run([PATHCL, "render", scene, "-o", os.path.join(WORK, "warm.exr"), "--quiet", "--lanes", str(l),
                 "--spp", "1", "--sampler", "independent"], pathcl_env())
        runs = {"pathcl-%d" % l: [] for l in lanes}
        runs.update({"mitsuba-" + v: [] for v in variants})
        version = None
        for _ in range(args.rounds):
            for l in lanes:
                runs["pathcl-%d" % l].append(pathcl_samples(scene, l, spp))
            for v in variants:
                s, version = mitsuba_samples(xml, v, spp, pixels)
                runs["mitsuba-" + v].append(s)
        med = {k: statistics.median(v) for k, v in runs.items() if v}
        entry = {"scene": os.path.relpath(scene, ROOT), "pixels": pixels, "spp": spp, "runs": runs,
                 "median_samples_per_second": med, "mitsuba_version": version}
        for v in variants if med else []:
            for l in lanes:
                entry["pathcl-%d_over_mitsuba-%s" % (l, v)] = med["pathcl-%d" % l] / med["mitsuba-" + v]
        if args.builds:
            entry["builds"] = {str(l): builds(scene, l) for l in lanes}
            for l in lanes:
                b = entry["builds"][str(l)]
                print("  %d lanes: kernel build %.0f ms cold, %.0f ms cached; largest stack frame %d bytes (%s), all "
                      "frames %d bytes" % (l, b["cold_ms"], b["cached_ms"], b["largest_frame_bytes"],
                                           b["largest_frame_function"], b["all_frames_bytes"]))
        result["scenes"][name] = entry
        print("%s (%d spp): %s" % (name, spp, ", ".join("%s %.2f M" % (k, v / 1e6) for k, v in med.items())))
        for v in variants if med else []:
            print("  against mitsuba-%s: %s" % (v, ", ".join(
                "%d lanes %.2fx" % (l, entry["pathcl-%d_over_mitsuba-%s" % (l, v)]) for l in lanes)))
    out_dir = os.path.join(ROOT, "bench", "results", "lanes")
    os.makedirs(out_dir, exist_ok=True)
    # A run with --builds is named apart, so that a timing run of the same minute keeps its file.
    out = os.path.join(out_dir, "%s%s.json" % (datetime.datetime.now().strftime("%Y-%m-%dT%H%M"),
                                               "-builds" if args.builds else ""))
    with open(out, "w") as f:
        json.dump(result, f, indent=1)
    print("results:", os.path.relpath(out, ROOT))


if __name__ == "__main__":
    main()
