#!/usr/bin/env python3
"""Where a pathcl render spends its time on the PoCL CPU device, by phase of the path loop.

Run through scripts/bench/profile (it installs perf and binutils). The kernel is built with debug
information (POCL_EXTRA_BUILD_FLAGS=-g) into fresh kernel caches, then `perf record --call-graph dwarf`
samples one render (cpu-clock). PoCL's compiler keeps trace_path, trace_bvh, sample4, sample_light, ...
as called functions, so every sample in the kernel's shared object unwinds to trace_path; `addr2line -i`
gives the line of trace_path it is at (or called from), and RANGES below turn lines into phases:
  closest-hit traversal   the trace_bvh call that finds the next vertex
  NEE shadow traversal    the trace_bvh call of the shadow ray
  NEE other               the rest of the next-event block: light choice and sampling, BSDF evaluation
                          for the light direction, shadow-ray set-up, MIS weight
  shading                 surface_at, material_at, the shading frame, bsdf_sample
  hit emission and MIS    emission met by BSDF sampling and its MIS weight, escaped rays
  sampler                 sample4 (random numbers)
  camera ray, path bookkeeping (the rest of trace_path: throughput, Russian roulette, next ray),
  film and launch loop    render_pass around trace_path (film accumulation, the work-item loop)
Samples outside the kernel are charged to PoCL's runtime, pathcl's host code, the OS or other objects.
The render is the same pixels as without -g; optimised code moves instructions across lines, so shares
are estimates to a few per cent.
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
INTEGRATOR = os.path.join(ROOT, "kernels", "integrator.cl")
PHASES = ["closest-hit traversal", "NEE shadow traversal", "NEE other", "shading", "hit emission and MIS",
          "sampler", "camera ray", "path bookkeeping", "film and launch loop", "traversal, caller not unwound",
          "other kernel code"]
CALLEES = {"sample4": "sampler", "camera_ray": "camera ray", "sample_light": "NEE other",
           "sample_area_light": "NEE other", "surface_at": "shading", "material_at": "shading",
           "bsdf_sample": "shading"}


# trace_path's source, cut into phases by marker text: (phase, first line's marker, marker of the line
# after the last; None: the first line alone). Checked in order; the first range holding a line wins.
RANGES = [("NEE shadow traversal", "trace_bvh(sc->nodes, sc->prims, &shadow", None),
          ("closest-hit traversal", "trace_bvh(sc->nodes, sc->prims, &ray", None),
          ("NEE other", "Next-event estimation", "BsdfSample bs;"),
          ("hit emission and MIS", "escaped_radiance(", "break;"),
          ("hit emission and MIS", "#ifdef PC_HAS_AREA_LIGHTS", "#endif"),
          ("shading", "Surface s = surface_at", "#ifdef PC_HAS_AREA_LIGHTS"),
          ("shading", "Material m = material_at", "float4 u_light"),
          ("shading", "BsdfSample bs;", "throughput *= bs.weight")]


def trace_path_ranges(path=INTEGRATOR):
    """[(phase, first line, line after the last)] in kernels/integrator.cl's trace_path, from RANGES."""
    lines = open(path).read().splitlines()
    start = next(i for i, l in enumerate(lines) if l.startswith("inline") and "trace_path(" in l)
    end = next(i for i in range(start, len(lines)) if lines[i].startswith("}"))
    out = []
    for phase, first, after in RANGES:
        a = next((i for i in range(start, end) if first in lines[i]), None)
        b = None if a is None else a + 1 if after is None else next(
            (i for i in range(a + 1, end) if after in lines[i]), None)
        if b is None:
            raise SystemExit("profile: cannot find %r .. %r in trace_path (%s)" % (first, after, path))
        out.append((phase, a + 1, b + 1))
    return out


def phase_of(frames, ranges):
    """frames: [(function, line)] innermost first, inlined and called frames alike. The phase is decided
    by the line of the sample's trace_path frame (where it is in the path loop, or the call it is in);
    calls from other lines go by the function called. A stack that did not unwind to trace_path goes by
    its innermost function."""
    names = [f for f, _ in frames]
    if "trace_path" not in names:
        for f in names:
            if f == "trace_bvh":
                return "traversal, caller not unwound"
            if f in CALLEES:
                return CALLEES[f]
            if f.startswith("_pocl_kernel_render_pass"):
                return "film and launch loop"
        return "other kernel code"
    i = names.index("trace_path")
    line = frames[i][1]
    for phase, a, b in ranges:
        if a <= line < b:
            return phase
    if i > 0 and names[i - 1] in CALLEES:
        return CALLEES[names[i - 1]]
    return "path bookkeeping"


def addr2line(so, addresses):
    """{address: [(function, line)]} for addresses in SO, innermost frame first."""
    out = {}
    addrs = sorted(addresses)
    for k in range(0, len(addrs), 2000):
        chunk = addrs[k:k + 2000]
        r = subprocess.run(["addr2line", "-i", "-f", "-a", "-e", so] + ["0x%x" % a for a in chunk],
                           capture_output=True, text=True, check=True)
        current = None
        lines = r.stdout.splitlines()
        j = 0
        while j < len(lines):
            if re.fullmatch(r"0x[0-9a-f]+", lines[j]):
                current = int(lines[j], 16)
                out[current] = []
                j += 1
                continue
            func, loc = lines[j], lines[j + 1] if j + 1 < len(lines) else "??:0"
            m = re.search(r":(\d+)", loc)
            out[current].append((func, int(m.group(1)) if m else 0))
            j += 2
    return out


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
               POCL_KERNEL_CACHE="1", POCL_EXTRA_BUILD_FLAGS="-g")
    render = [args.pathcl, "render", args.scene, "-q", "-o", os.path.join(work, "out.exr")] + render_args
    # The first render builds the kernel and PoCL's work-group function, so the profiled one only renders.
    subprocess.run(render + ["--spp", "1"], env=env, check=True)
    stats = os.path.join(work, "stats.json")
    data = os.path.join(work, "perf.data")
    subprocess.run(["perf", "record", "-q", "-e", "cpu-clock", "-F", str(args.frequency), "--call-graph",
                    "dwarf,16384", "-o", data, "--"] + render + ["--spp", str(args.spp), "--stats", stats],
                   env=env, check=True, stdout=subprocess.DEVNULL)
    r = subprocess.run(["perf", "script", "-i", data, "-F", "ip,sym,dso", "--no-inline"], capture_output=True,
                       text=True, check=True)

    # Each sample: its stack as (address within the object, object), innermost first.
    stacks = collections.Counter()
    frames = []
    for line in r.stdout.splitlines() + [""]:
        m = re.match(r"\s*([0-9a-f]+)\s+.*\((.*)\)\s*$", line)
        if m:
            frames.append((int(m.group(1), 16), m.group(2)))
        elif frames:
            stacks[tuple(frames)] += 1
            frames = []

    pocl_cache = env["POCL_CACHE_DIR"]
    by_dso = collections.Counter()
    kernel_stacks = collections.Counter()
    for stack, n in stacks.items():
        dso = stack[0][1]
        if dso.startswith(pocl_cache):
            # Return addresses point after the call; the call itself is one byte earlier.
            kernel_stacks[tuple((a if k == 0 else a - 1, d) for k, (a, d) in enumerate(stack) if d == dso)] += n
        elif "pocl" in os.path.basename(dso):
            by_dso["PoCL runtime"] += n
        elif dso.endswith("/pathcl") or re.search(r"lib(OpenCL|stdc\+\+|c|m|gcc_s|OpenEXR|Imath|z)[-.]", dso):
            by_dso["host (pathcl, its libraries)"] += n
        elif "kernel.kallsyms" in dso:
            by_dso["OS kernel"] += n
        else:
            by_dso["other: " + os.path.basename(dso)] += n

    ranges = trace_path_ranges()
    phases = collections.Counter()
    for so in {st[0][1] for st in kernel_stacks}:
        lines = addr2line(so, {a for st in kernel_stacks if st[0][1] == so for a, _ in st})
        for st, n in kernel_stacks.items():
            if st[0][1] == so:
                phases[phase_of([f for a, _ in st for f in lines.get(a, [])], ranges)] += n

    in_kernel = sum(phases.values())
    total = in_kernel + sum(by_dso.values())
    with open(stats) as f:
        s = json.load(f)
    if in_kernel == 0:
        raise SystemExit("profile: no samples in the kernel (was it built with debug information?)")
    result = dict(scene=args.scene, spp=args.spp, samples=total, kernel_samples=in_kernel,
                  render_seconds=s["render_seconds"], kernel_seconds=s.get("kernel_seconds"),
                  samples_per_second=s["samples_per_second"],
                  kernel_phases={p: phases[p] / in_kernel for p in PHASES},
                  outside_kernel={k: v / total for k, v in by_dso.items()}, kernel_share=in_kernel / total)
    print("%s, %d spp: %.2f s render, %.0f k samples/s; %d perf samples, %.1f %% in the kernel" % (
        args.scene, args.spp, s["render_seconds"], s["samples_per_second"] / 1e3, total, 100 * in_kernel / total))
    print("| phase | share of kernel time |\n|---|---|")
    for p in PHASES:
        print("| %s | %.1f %% |" % (p, 100 * phases[p] / in_kernel))
    for k, v in sorted(by_dso.items(), key=lambda kv: -kv[1]):
        print("outside the kernel: %s %.1f %% of all samples" % (k, 100 * v / total))
    if args.json:
        with open(args.json, "w") as f:
            json.dump(result, f, indent=1)
    shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
