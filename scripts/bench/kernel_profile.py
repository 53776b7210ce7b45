#!/usr/bin/env python3
"""Where a pathcl render spends its time on the PoCL CPU device, by phase of the path loop.

Run through scripts/bench/profile (it installs perf and binutils). The kernel is built into fresh kernel
caches and `perf record` samples one render (cpu-clock). PoCL's compiler keeps most functions of the
megakernel as called functions (trace_packet, path_shade_lanes, light_choice_lanes, ...; kernels/
lanes.cl forces the small ones inline), so each sample in the kernel's shared object is charged to the
phase of the function it is in (FUNCTIONS below, by name, whatever the lane width; kernels/integrator.cl):
  traversal               the packet and single-ray traversals of closest-hit and shadow rays
  light choice            the light tree (light_choice_lanes)
  light sampling and MIS  sampling a light, the MIS densities of lights hit
  surface and material    the surface at a hit, the material and its textures
  BSDF and path           path_shade_lanes itself: the frame, the BSDF dispatch, NEE and roulette
  sampler                 sample4_lanes and the samplers it calls
  camera ray              camera_ray_lanes and the filters
  work item loop          render_pass: tasks, shadow-ray results, the ring of finished samples
Functions not listed are shown by name. Samples outside the kernel are charged to PoCL's runtime,
pathcl's host code, the OS or other objects. Shares are of the samples; the same pixels as a render without
the profiler.
"""
import argparse
import collections
import json
import os
import re
import shutil
import subprocess
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

# (phase, function name prefixes; mangled names contain the plain name after their length prefix)
FUNCTIONS = [
    ("traversal", ["trace_packet", "packet_leaf", "packet_prim_lane", "packet_subtrees_by_lane", "packet_by_lane",
                   "packet_ray_lane",
                   "trace_tree", "trace_lanes", "trace_scene", "trace_bvh", "trace_instance", "intersect_"]),
    ("light choice", ["light_choice_lanes", "light_bounds_importance_lanes", "light_node_field_lanes"]),
    ("light sampling and MIS", ["sample_light_lanes", "sample_area_light_lanes", "sample_sphere_cone_lanes",
                                "light_pdf_lanes", "environment_light_pdf_lanes", "env_", "escaped_radiance_lanes"]),
    ("surface and material", ["scene_surface_lanes", "material_at_lanes", "texture_", "surface_uv", "place_surface"]),
    ("BSDF and path", ["path_shade_lanes", "bsdf_", "pc_sincos", "pc_reduce", "pc_powr", "ggx_", "fresnel_",
                       "diffuse_", "oren_nayar_", "phong_", "mirror_", "dielectric_", "rough_conductor_",
                       "plastic_"]),
    ("sampler", ["sample4_lanes", "stratified_pair", "owen_scrambled", "sobol_bits", "permute_index"]),
    ("camera ray", ["camera_ray_lanes", "sample_filter", "erf_inverse", "pc_erf", "pc_exp2", "path_begin_lanes"]),
    ("work item loop", ["_pocl_kernel_render_pass", "render_pass", "accumulate_sample", "add_unit_stats"]),
]


def phase_of(symbol):
    """The phase of a kernel function (mangled or not), or the function's own name."""
    plain = re.sub(r"^_Z\d+", "", symbol)
    for phase, prefixes in FUNCTIONS:
        if any(plain.startswith(p) for p in prefixes):
            return phase
    return "other: " + plain[:40]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scene")
    ap.add_argument("--spp", type=int, default=16)
    ap.add_argument("--frequency", type=int, default=2000, help="perf samples per second per core")
    ap.add_argument("--pathcl", default=os.path.join(ROOT, os.environ.get("PATHCL_BUILD", "build"), "pathcl"))
    ap.add_argument("--json", help="write the shares as JSON")
    args, render_args = ap.parse_known_args()  # the rest goes to `pathcl render` (e.g. --sampler independent)

    work = tempfile.mkdtemp(prefix="pathcl-profile-")
    env = dict(os.environ, PATHCL_KERNEL_CACHE=os.path.join(work, "kc"), POCL_CACHE_DIR=os.path.join(work, "pocl"),
               POCL_KERNEL_CACHE="1")
    render = [args.pathcl, "render", args.scene, "-q", "-o", os.path.join(work, "out.exr")] + render_args
    # The first render builds the kernel and PoCL's work-group function, so the profiled one only renders.
    subprocess.run(render + ["--spp", "1"], env=env, check=True)
    stats = os.path.join(work, "stats.json")
    data = os.path.join(work, "perf.data")
    subprocess.run(["perf", "record", "-q", "-e", "cpu-clock", "-F", str(args.frequency), "-o", data, "--"] + render +
                   ["--spp", str(args.spp), "--stats", stats], env=env, check=True, stdout=subprocess.DEVNULL)
    r = subprocess.run(["perf", "script", "-i", data, "-F", "ip,sym,dso"], capture_output=True, text=True, check=True)

    pocl_cache = env["POCL_CACHE_DIR"]
    phases, functions, by_dso = collections.Counter(), collections.Counter(), collections.Counter()
    for line in r.stdout.splitlines():
        m = re.match(r"\s*[0-9a-f]+\s+(\S+)\s+\((.*)\)\s*$", line)
        if not m:
            continue
        symbol, dso = m.groups()
        if dso.startswith(pocl_cache):
            phases[phase_of(symbol)] += 1
            functions[re.sub(r"^_Z\d+", "", symbol)[:60]] += 1
        elif "pocl" in os.path.basename(dso):
            by_dso["PoCL runtime"] += 1
        elif dso.endswith("/pathcl") or re.search(r"lib(OpenCL|stdc\+\+|c|m|gcc_s|OpenEXR|Imath|z)[-.]", dso):
            by_dso["host (pathcl, its libraries)"] += 1
        elif "kernel.kallsyms" in dso:
            by_dso["OS kernel"] += 1
        else:
            by_dso["other: " + os.path.basename(dso)] += 1

    in_kernel = sum(phases.values())
    total = in_kernel + sum(by_dso.values())
    with open(stats) as f:
        s = json.load(f)
    if in_kernel == 0:
        raise SystemExit("profile: no samples in the kernel")
    result = dict(scene=args.scene, spp=args.spp, lanes=s.get("lanes"), samples=total, kernel_samples=in_kernel,
                  render_seconds=s["render_seconds"], kernel_seconds=s.get("kernel_seconds"),
                  samples_per_second=s["samples_per_second"],
                  kernel_phases={p: n / in_kernel for p, n in phases.most_common()},
                  kernel_functions={f: n / in_kernel for f, n in functions.most_common(20)},
                  outside_kernel={k: v / total for k, v in by_dso.items()}, kernel_share=in_kernel / total)
    print("%s, %d spp, %s lanes: %.2f s render, %.0f k samples/s; %d perf samples, %.1f %% in the kernel" % (
        args.scene, args.spp, s.get("lanes"), s["render_seconds"], s["samples_per_second"] / 1e3, total,
        100 * in_kernel / total))
    print("| phase | share of kernel time |\n|---|---|")
    for p, n in phases.most_common():
        print("| %s | %.1f %% |" % (p, 100 * n / in_kernel))
    for k, v in sorted(by_dso.items(), key=lambda kv: -kv[1]):
        print("outside the kernel: %s %.1f %% of all samples" % (k, 100 * v / total))
    if args.json:
        with open(args.json, "w") as f:
            json.dump(result, f, indent=1)
    shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
