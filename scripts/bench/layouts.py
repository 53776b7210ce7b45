"""BVH layouts side by side (issue 15; a benchmark, not a test): `pathcl rays` with the 4-, 8- and 16-wide
BVH (PATHCL_BVH_WIDTH), and with the 16-wide one (the default on AVX-512 CPUs, as on the machine this was
written on) as packets of 8 and 16 rays (--lanes), against Embree's rtcIntersect1 (bench/embree_rays.cpp, 1
and 2 threads, and 2 threads with RTC_SCENE_FLAG_ROBUST) on the same camera and diffuse-bounce rays of the
benchmark suite's 524,288-triangle terrain, and render samples/s of the suite's scenes with each layout.
Rounds alternate A B C A B C; figures are medians over the rounds. Checks that the layouts and the packets
give the same hit records as each other, and counts what a ray visits on pathcl's 8- and 16-wide trees and
on one built by Embree's builder (bench/bvh_visits.cpp).
Usage: scripts/bench/layouts [--rounds N] [--size PIXELS] [--bar ROUNDS]   (results: bench/results/layouts/*.json, beside and
not among the peer runs that scripts/bench/report.py reads)
"""
import argparse
import datetime
import json
import os
import platform
import re
import statistics
import subprocess
import sys

from avx2 import AVX2_ENV

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
BUILD = os.path.join(ROOT, "build")
PATHCL = os.path.join(BUILD, "pathcl")
MAKE_RAYS = os.path.join(BUILD, "make_rays")
EMBREE_RAYS = os.path.join(BUILD, "embree_rays")
BVH_VISITS = os.path.join(BUILD, "bvh_visits")
WIDTHS = (4, 8, 16)
BAR_WIDTH = 16  # the layout that the bar and the packets measure: the CPU default with AVX-512
# --avx2: AVX2 code on an AVX-512 machine (scripts/bench/avx2.py; Embree runs its AVX2 code, the bar measures
# the 8-wide tree that pathcl picks without AVX-512); main() sets these.
AVX2 = False
EMBREE_ISA = None


def run(cmd, env=None):
    r = subprocess.run(cmd, capture_output=True, text=True, env=env)
    if r.returncode:
        sys.exit("%s: exit %d\n%s" % (" ".join(cmd), r.returncode, r.stderr[-2000:]))
    return r.stdout


def bvh_visits(obj, rays):
    """bvh_visits' per-ray averages: {tree: {all|hit|miss: {rays, nodes, leaves, blocks}}}, and its tree sizes."""
    out, visits, trees = run([BVH_VISITS, obj, rays]), {}, {}
    for line in out.splitlines():
        m = re.match(r"\[(\w+)\] (all|hit|miss) +rays +(\d+) +nodes/ray +([\d.]+) +leaves/ray +([\d.]+) +blocks/ray +([\d.]+)", line)
        if m:
            visits.setdefault(m[1], {})[m[2]] = {"rays": int(m[3]), "nodes": float(m[4]), "leaves": float(m[5]),
                                                 "blocks": float(m[6])}
        m = re.match(r"\[(\w+)\] nodes (\d+) +leaves (\d+) +blocks (\d+) .*SAH\(node=1,block=1\) ([\d.]+)", line)
        if m:
            trees[m[1]] = {"nodes": int(m[2]), "leaves": int(m[3]), "blocks": int(m[4]), "sah": float(m[5])}
    return {"per_ray": visits, "trees": trees}


def embree_rays(obj, rays, threads, compare=None, robust=False):
    """embree_rays' JSON for the ray file with `threads` threads (5 repetitions); compare: pathcl's hit file;
    robust: RTC_SCENE_FLAG_ROBUST (watertight, like pathcl's tests)."""
    cmd = [EMBREE_RAYS, obj, rays, "--threads", str(threads), "--repeat", "5", "--robust", str(int(robust))]
    if EMBREE_ISA:
        cmd += ["--isa", EMBREE_ISA]
    return json.loads(run(cmd + (["--compare", compare] if compare else [])))


def with_width(width):
    env = dict(os.environ)
    if AVX2:
        env.update(AVX2_ENV)
    env["PATHCL_BVH_WIDTH"] = str(width)
    return env


def pathcl_rays(scene, rays, width, work, hits=None, lanes=1):
    stats = os.path.join(work, "stats.json")
    cmd = [PATHCL, "rays", scene, "--rays", rays, "--repeat", "5", "--stats", stats, "--lanes", str(lanes)]
    if hits:
        cmd += ["--hits", hits]
    run(cmd, with_width(width))
    with open(stats) as f:
        return json.load(f)["rays_per_second_kernel"]


def resized(scene, size, out):
    """A copy of the scene file with a size x size film."""
    with open(scene) as f:
        j = json.load(f)
    j["camera"]["width"] = j["camera"]["height"] = size
    with open(out, "w") as f:
        json.dump(j, f)
    return out


def pathcl_samples(scene, width, work, spp):
    stats = os.path.join(work, "render-stats.json")
    run([PATHCL, "render", scene, "-o", os.path.join(work, "render.exr"), "--spp", str(spp), "--quiet", "--stats",
         stats], with_width(width))
    with open(stats) as f:
        return json.load(f)["samples_per_second"]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--size", type=int, default=768, help="terrain film side: camera rays, 2 a pixel")
    ap.add_argument("--bar", type=int, default=0, metavar="ROUNDS",
                    help="only the diffuse-bounce bar: the 16-wide single ray against Embree with 2 threads, alternated "
                         "ROUNDS times (the per-round ratios narrow the figure on a noisy machine)")
    ap.add_argument("--avx2", action="store_true",
                    help="AVX2 code on an AVX-512 machine (scripts/bench/avx2.py), Embree with isa=avx2, the bar and "
                         "packets on the 8-wide tree: a stand-in where no AVX2 machine is at hand")
    args = ap.parse_args()
    global AVX2, EMBREE_ISA, BAR_WIDTH
    if args.avx2:
        AVX2, EMBREE_ISA, BAR_WIDTH = True, "avx2", 8
    work = os.path.join(BUILD, "bench-layouts")
    os.makedirs(work, exist_ok=True)
    scenes = os.path.join(work, "scenes")
    run([PATHCL, "bench", "--write-scenes", scenes])
    big = resized(os.path.join(scenes, "terrain.json"), args.size, os.path.join(scenes, "terrain-rays.json"))
    obj = os.path.join(work, "terrain.obj")
    run([PATHCL, "info", big, "--dump-obj", obj])
    cam, cam_hits, bounce = (os.path.join(work, n) for n in ("camera.rays", "camera.hits", "bounce.rays"))
    run([MAKE_RAYS, "camera", big, cam, "2"])
    run([PATHCL, "rays", big, "--rays", cam, "--hits", cam_hits, "--repeat", "1"], with_width(4))
    run([MAKE_RAYS, "bounce", big, cam, cam_hits, bounce])

    result = {"date": datetime.datetime.now().isoformat(timespec="seconds"), "host": platform.node(), "avx2": args.avx2,
              "pathcl": run([PATHCL, "--version"]).splitlines()[0], "rounds": args.rounds, "rays": {}, "samples": {}}
    if args.bar:
        result["bar"] = bar(big, obj, bounce, work, args.bar)
        save(result)
        return
    for name, rays in (("camera", cam), ("diffuse_bounce", bounce)):
        runs = {"bvh4": [], "bvh8": [], "bvh16": [], "packet8": [], "packet16": [], "embree-1": [], "embree-2": [],
                "embree-2-robust": []}
        hits = {w: os.path.join(work, "%s-%d.hits" % (name, w)) for w in WIDTHS}
        packet_hits = {n: os.path.join(work, "%s-packet%d.hits" % (name, n)) for n in (8, 16)}
        for _ in range(args.rounds):
            for w in WIDTHS:
                runs["bvh%d" % w].append(pathcl_rays(big, rays, w, work, hits[w]))
            for n in (8, 16):
                runs["packet%d" % n].append(pathcl_rays(big, rays, BAR_WIDTH, work, packet_hits[n], lanes=n))
            for threads in (1, 2):
                e = embree_rays(obj, rays, threads, hits[8])
                runs["embree-%d" % threads].append(e["rays_per_second"])
                same = e["same_primitive_fraction"]
            e = embree_rays(obj, rays, 2, hits[8], robust=True)
            runs["embree-2-robust"].append(e["rays_per_second"])
            same_robust = e["same_primitive_fraction"]
        visits = bvh_visits(obj, rays)
        v = {t: visits["per_ray"][t]["all"] for t in ("pathcl", "pathcl16", "embree")}
        print("%s rays visit %.2f nodes and %.2f blocks on pathcl's 8-wide tree, %.2f and %.2f on its 16-wide one, "
              "%.2f and %.2f on Embree's builder's" %
              (name, v["pathcl"]["nodes"], v["pathcl"]["blocks"], v["pathcl16"]["nodes"], v["pathcl16"]["blocks"],
               v["embree"]["nodes"], v["embree"]["blocks"]))
        records = []
        for path in [hits[w] for w in WIDTHS] + [packet_hits[8], packet_hits[16]]:
            with open(path, "rb") as f:
                records.append(f.read())
        identical = all(r == records[0] for r in records)
        med = {k: statistics.median(v) for k, v in runs.items()}
        # Each round's own ratio: the two programs a few seconds apart, so their spread shows this machine's.
        by_round = [p / e for p, e in zip(runs["bvh16"], runs["embree-2"])]
        result["rays"][name] = {"median_rays_per_second": med, "runs": runs, "layouts_identical_hits": identical,
                                "embree_same_primitive_fraction": same,
                                "embree_robust_same_primitive_fraction": same_robust, "visits": visits,
                                "bvh16_over_embree2": med["bvh16"] / med["embree-2"],
                                "bvh8_over_embree2": med["bvh8"] / med["embree-2"],
                                "bvh16_over_embree2_robust": med["bvh16"] / med["embree-2-robust"],
                                "bvh16_over_embree2_by_round": by_round,
                                "bvh8_over_bvh4": med["bvh8"] / med["bvh4"],
                                "bvh16_over_bvh8": med["bvh16"] / med["bvh8"],
                                "packet8_over_bvh16": med["packet8"] / med["bvh16"],
                                "packet16_over_bvh16": med["packet16"] / med["bvh16"]}
        print("%s rays: 4-wide %.2f, 8-wide %.2f, 16-wide %.2f, packets of 8 %.2f, of 16 %.2f, Embree 1 thread %.2f, "
              "2 threads %.2f, robust %.2f Mrays/s; 16-wide / Embree-2 %.2f (rounds %.2f-%.2f), 8-wide / Embree-2 "
              "%.2f, 16-wide / robust %.2f; hit records of the layouts and packets identical: %s; same primitive as "
              "Embree: %.4f, robust %.4f" %
              (name, med["bvh4"] / 1e6, med["bvh8"] / 1e6, med["bvh16"] / 1e6, med["packet8"] / 1e6,
               med["packet16"] / 1e6, med["embree-1"] / 1e6, med["embree-2"] / 1e6, med["embree-2-robust"] / 1e6,
               med["bvh16"] / med["embree-2"], min(by_round), max(by_round), med["bvh8"] / med["embree-2"],
               med["bvh16"] / med["embree-2-robust"], identical, same, same_robust))
    for scene, size, spp in (("cornell-box", 256, 64), ("glass-metal", 256, 64), ("terrain", 256, 16)):
        runs = {"bvh%d" % w: [] for w in WIDTHS}
        file = resized(os.path.join(scenes, scene + ".json"), size, os.path.join(scenes, "%s-%d.json" % (scene, size)))
        for _ in range(args.rounds):
            for w in WIDTHS:
                runs["bvh%d" % w].append(pathcl_samples(file, w, work, spp))
        med = {k: statistics.median(v) for k, v in runs.items()}
        result["samples"][scene] = {"size": size, "spp": spp, "median_samples_per_second": med, "runs": runs}
        print("%s %dx%d, %d spp: 4-wide %.3f, 8-wide %.3f, 16-wide %.3f Msamples/s (%.2fx, %.2fx)" %
              (scene, size, size, spp, med["bvh4"] / 1e6, med["bvh8"] / 1e6, med["bvh16"] / 1e6,
               med["bvh8"] / med["bvh4"], med["bvh16"] / med["bvh8"]))
    save(result)


def bar(scene, obj, rays, work, rounds):
    """pathcl's 16-wide single ray and Embree with 2 threads on the bounce rays, alternated (who goes first
    swaps each round)."""
    key = "bvh%d" % BAR_WIDTH
    runs = {key: [], "embree-2": []}
    embree = lambda: embree_rays(obj, rays, 2)["rays_per_second"]
    for i in range(rounds):
        if i % 2 == 0:
            runs[key].append(pathcl_rays(scene, rays, BAR_WIDTH, work))
            runs["embree-2"].append(embree())
        else:
            runs["embree-2"].append(embree())
            runs[key].append(pathcl_rays(scene, rays, BAR_WIDTH, work))
    ratios = sorted(p / e for p, e in zip(runs[key], runs["embree-2"]))
    med = {k: statistics.median(v) for k, v in runs.items()}
    out = {"runs": runs, "median_rays_per_second": med, key + "_over_embree2": med[key] / med["embree-2"],
           "round_ratio_median": statistics.median(ratios), "round_ratio_quartiles": [ratios[len(ratios) // 4],
                                                                                    ratios[3 * len(ratios) // 4]],
           "rounds_above_1": sum(r > 1 for r in ratios)}
    print("diffuse_bounce bar, %d rounds: %d-wide %.2f, Embree 2 threads %.2f Mrays/s, %.3fx; per round %.3fx "
          "(quartiles %.3f-%.3f, %d above 1)" % (rounds, BAR_WIDTH, med[key] / 1e6, med["embree-2"] / 1e6,
                                                 out[key + "_over_embree2"], out["round_ratio_median"],
                                                 *out["round_ratio_quartiles"], out["rounds_above_1"]))
    return out


def save(result):
    os.makedirs(os.path.join(ROOT, "bench", "results", "layouts"), exist_ok=True)
    out = os.path.join(ROOT, "bench", "results", "layouts", "%s.json" % datetime.datetime.now().strftime("%Y-%m-%dT%H%M"))
    with open(out, "w") as f:
        json.dump(result, f, indent=1)
    print("results:", os.path.relpath(out, ROOT))


if __name__ == "__main__":
    main()
