#!/usr/bin/env python3
"""Runs the pathcl speed benchmark and prints a table; writes bench/out/results.json.

Every figure is a median over runs; the device, scene, triangle count and build times are reported
beside it. Called by scripts/bench/own after the build.
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PATHCL = os.path.join(ROOT, "build", "pathcl")
MAKE_RAYS = os.path.join(ROOT, "build", "make_rays")
DATA = os.path.join(ROOT, "bench", "data")
OUT = os.path.join(ROOT, "bench", "out")


def run(cmd, env=None):
    result = subprocess.run(cmd, capture_output=True, text=True, env=env)
    if result.returncode != 0:
        sys.exit(f"bench: {' '.join(cmd)} failed ({result.returncode}):\n{result.stderr}")
    return result.stdout


def stats_of(cmd, env=None):
    path = os.path.join(OUT, "last-stats.json")
    run(cmd + ["--stats", path], env)
    with open(path) as f:
        return json.load(f)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--device", default="", help="device index or name substring")
    ap.add_argument("--spp", type=int, default=32, help="Cornell box samples per pixel")
    ap.add_argument("--runs", type=int, default=3, help="runs per figure (the median is reported)")
    args = ap.parse_args()
    os.makedirs(OUT, exist_ok=True)
    device = ["--device", args.device] if args.device else []
    results = {}

    # Kernel build: cold (empty cache; PoCL's own kernel cache off too) and from pathcl's binary cache,
    # for the Cornell box's specialised kernel and for the unspecialised one.
    cornell = os.path.join(ROOT, "scenes", "cornell-box.json")
    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, PATHCL_KERNEL_CACHE=cache, POCL_KERNEL_CACHE="0")
        quick = [PATHCL, "render", cornell, "-o", os.path.join(OUT, "build-check.exr"), "--spp", "1", "--quiet"] + device
        cold = stats_of(quick, env)
        warm = stats_of(quick, env)
        cold_all = stats_of(quick + ["--all-features"], env)
    results["kernel_build_ms_cold_all_features"] = cold_all["kernel_build_ms"]
    results["kernel_build_ms_cold"] = cold["kernel_build_ms"]
    results["kernel_build_ms_cached"] = warm["kernel_build_ms"]
    results["kernel_cached_hit"] = warm["kernel_from_cache"]

    # Cornell box at 512 x 512.
    runs = [stats_of([PATHCL, "render", cornell, "-o", os.path.join(OUT, "cornell-box.exr"), "--spp", str(args.spp),
                      "--quiet"] + device) for _ in range(args.runs)]
    results["device"] = runs[0]["device"]
    results["cornell"] = {
        "width": runs[0]["width"], "height": runs[0]["height"], "spp": args.spp,
        "samples_per_second": statistics.median(r["samples_per_second"] for r in runs),
        "rays_per_second": statistics.median(r["rays_per_second"] for r in runs),
        "render_seconds": [r["render_seconds"] for r in runs],
    }

    # Ray throughput on the generated terrain scene.
    scene = os.path.join(DATA, "terrain.json")
    if not os.path.exists(scene):
        run([sys.executable, os.path.join(ROOT, "scripts", "make-bench-scene"), DATA])
    camera, hits, bounce = (os.path.join(DATA, n) for n in ("camera.rays", "camera.hits", "bounce.rays"))
    run([MAKE_RAYS, "camera", scene, camera, "2"])
    run([PATHCL, "rays", scene, "--rays", camera, "--hits", hits, "--repeat", "1"] + device)
    run([MAKE_RAYS, "bounce", scene, camera, hits, bounce])
    for name, rays in (("camera_rays", camera), ("diffuse_bounce_rays", bounce)):
        samples = []
        for _ in range(args.runs):
            s = stats_of([PATHCL, "rays", scene, "--rays", rays, "--repeat", "5"] + device)
            samples.append(s)
        results[name] = {
            "rays": samples[0]["rays"], "hits": samples[0]["hits"],
            "rays_per_second_kernel": statistics.median(s["rays_per_second_kernel"] for s in samples),
            "rays_per_second_wall": statistics.median(s["rays_per_second_wall"] for s in samples),
        }
    results["terrain"] = {k: samples[0][k] for k in ("triangles", "bvh_nodes", "bvh_depth", "bvh4_nodes",
                                                     "bvh4_depth", "sah_cost", "bvh_build_ms", "scene_load_ms")}

    with open(os.path.join(OUT, "results.json"), "w") as f:
        json.dump(results, f, indent=2)
    c, t = results["cornell"], results["terrain"]
    print(f"device: {results['device']}")
    print(f"kernel build (Cornell box): cold {results['kernel_build_ms_cold']:.0f} ms, "
          f"cached {results['kernel_build_ms_cached']:.0f} ms; all-features kernel cold "
          f"{results['kernel_build_ms_cold_all_features']:.0f} ms")
    print(f"Cornell box {c['width']}x{c['height']}, {c['spp']} spp: {c['samples_per_second'] / 1e6:.3f} Msamples/s, "
          f"{c['rays_per_second'] / 1e6:.2f} Mrays/s (median of {args.runs})")
    print(f"terrain: {t['triangles']} triangles, {t['bvh_nodes']} nodes (4-wide: {t['bvh4_nodes']}), "
          f"SAH cost {t['sah_cost']:.2f}, "
          f"BVH build {t['bvh_build_ms']:.0f} ms (load + clean-up {t['scene_load_ms']:.0f} ms)")
    for name in ("camera_rays", "diffuse_bounce_rays"):
        r = results[name]
        print(f"{name}: {r['rays']} rays, {r['hits']} hits: {r['rays_per_second_kernel'] / 1e6:.2f} Mrays/s kernel, "
              f"{r['rays_per_second_wall'] / 1e6:.2f} Mrays/s wall (median of {args.runs} x 5)")
    print(f"results: {os.path.relpath(os.path.join(OUT, 'results.json'), ROOT)}")


if __name__ == "__main__":
    main()
