#!/usr/bin/env python3
"""pathcl against Cycles, Mitsuba 3, LuxCoreRender and Embree on the same scenes, on this machine, in one run.

Run through scripts/bench/peers (it installs the peers). For each scene:
1. `pathcl info --dump-obj` and the exporters (export_*.py) give every peer the same triangles, materials,
   lights, camera and depth.
2. Reference: pathcl at --ref-spp with per-pixel variance, accepted if a per-pixel z-test against a
   Cycles render (--ref-cycles-batches seeds of --ref-cycles-spp, their spread giving its variance) passes
   for >= 99 % of pixels.
3. Per run (A B A B order: every renderer once per run): a convergence series (relMSE against render time
   at --series spp) and one render per time budget (the renderer's own time limit).
4. Each renderer's mean image (its final series images averaged over runs) against the reference.
5. Traversal: `pathcl rays` against build/embree_rays (1 and 2 threads) on camera and diffuse-bounce rays.
--avx2: pathcl, Mitsuba's LLVM variants and Embree run AVX2 code on an AVX-512 machine (scripts/bench/avx2.py;
the other peers run their own choice); write such a run to bench/results/supplementary/ with --no-docs.
relMSE everywhere: mean over pixels and channels of (x - ref)^2 / (ref^2 + 0.01), as `pathcl compare`.
Writes bench/results/<date>T<hhmm>-<machine>.json and regenerates docs/benchmarks.md (report.py) from every
results file there, each scene from the newest run that has it.
"""
import argparse
import datetime
import glob
import json
import math
import os
import platform
import shutil
import statistics
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, HERE)
import export_cycles  # noqa: E402
import export_luxcore  # noqa: E402
import export_mitsuba  # noqa: E402
import scene_model  # noqa: E402
from avx2 import AVX2_ENV  # noqa: E402

BUILD = os.path.join(ROOT, os.environ.get("PATHCL_BUILD", "build"))
PATHCL = os.path.join(BUILD, "pathcl")
MAKE_RAYS = os.path.join(BUILD, "make_rays")
EMBREE_RAYS = os.path.join(ROOT, "build", "embree_rays")
RENDERERS = ["pathcl", "cycles", "mitsuba-scalar_rgb", "mitsuba-llvm_ad_rgb", "luxcore-PATHCPU", "luxcore-PATHOCL"]
MITSUBA_TIMEOUT = ("not measured: Mitsuba's integrator timeout stops rendering block by block, so the blocks it has"
                   " not reached stay black (relMSE 0.23 at both 5 s and 30 s in the 2026-11-23 run); it is no"
                   " progressive time budget. Use the series-based columns.")
NO_ICD = os.path.join(ROOT, "build", "no-opencl-icd")
AVX2 = False  # --avx2 (main sets it)


def log(*a):
    print(*a, file=sys.stderr, flush=True)


def read_rgb(path, variance=False):
    import numpy as np
    if path.endswith(".npy"):  # LuxCore snapshots: height x width x RGB
        return np.load(path).astype(np.float64).transpose(2, 0, 1)
    import OpenEXR
    ch = OpenEXR.File(path, separate_channels=True).channels()
    rgb = np.stack([ch[c].pixels.astype(np.float64) for c in "RGB"])
    if variance:
        return rgb, np.stack([ch["variance." + c].pixels.astype(np.float64) for c in "RGB"])
    return rgb


def relmse(x, ref):
    import numpy as np
    return float(np.mean((x - ref) ** 2 / (ref ** 2 + 0.01)))


def run(cmd, env=None, timeout=None):
    t = time.time()
    r = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=timeout)
    return r, time.time() - t


def bench_lines(stdout):
    return [json.loads(l[len("PATHCL_BENCH "):]) for l in stdout.splitlines() if l.startswith("PATHCL_BENCH ")]


def error_tail(r):
    text = (r.stderr or "") + (r.stdout or "")
    lines = [l for l in text.splitlines() if l.strip() and not l.startswith("  - ")]
    first = [l for l in lines if any(k in l for k in ("LLVM ERROR", "Error", "error:", "free(", "corruption"))][:2]
    return "exit %d: %s" % (r.returncode, " | ".join(first + lines[-3:]))


# --- renderers -------------------------------------------------------------------------------------

class Renderer:
    """Runs one renderer on one scene: series(seed, spps) and budget(seed, seconds) -> dicts, or raise."""

    def __init__(self, name, scene, work):
        self.name, self.scene, self.work = name, scene, work
        os.makedirs(work, exist_ok=True)

    def out(self, tag):
        return os.path.join(self.work, tag + ".exr")


class Pathcl(Renderer):
    def _render(self, seed, extra, tag):
        stats, conv = os.path.join(self.work, tag + ".json"), os.path.join(self.work, tag + ".csv")
        cmd = [PATHCL, "render", self.scene.json, "--seed", str(seed), "-o", self.out(tag), "--stats", stats, "-q",
               "--convergence", conv, "--reference", self.scene.reference] + extra
        r, wall = run(cmd)
        if r.returncode:
            raise RuntimeError(error_tail(r))
        with open(stats) as f:
            s = json.load(f)
        import csv
        with open(conv) as f:
            rows = list(csv.DictReader(f))
        setup = s["scene_load_ms"] / 1e3 + s["bvh_build_ms"] / 1e3 + s["kernel_build_ms"] / 1e3
        return s, rows, wall, setup

    def series(self, seed, spps):
        s, rows, wall, setup = self._render(seed, ["--spp", str(max(spps))], "series-%d" % seed)
        points = {}
        for row in rows:
            points[int(row["spp"])] = dict(spp=int(row["spp"]), render_seconds=float(row["render_seconds"]),
                                           relmse=float(row["relmse"]))
        return dict(points=sorted(points.values(), key=lambda p: p["spp"]), setup_seconds=setup,
                    process_overhead_seconds=wall - s["render_seconds"], image=self.out("series-%d" % seed),
                    samples_per_second=s["samples_per_second"], kernel_build_ms=s["kernel_build_ms"],
                    kernel_from_cache=s["kernel_from_cache"], bvh_build_ms=s["bvh_build_ms"],
                    scene_load_ms=s["scene_load_ms"], kernel_seconds=s["kernel_seconds"],
                    render_seconds=s["render_seconds"], launches=s["launches"], rays_per_second=s["rays_per_second"])

    def budget(self, seed, seconds):
        s, rows, wall, setup = self._render(seed, ["--time", str(seconds)], "budget-%g-%d" % (seconds, seed))
        return dict(render_seconds=s["render_seconds"], setup_seconds=setup, wall_seconds=wall, spp=s["spp"],
                    relmse=float(rows[-1]["relmse"]))


class Cycles(Renderer):
    def __init__(self, name, scene, work):
        super().__init__(name, scene, work)
        self.script = export_cycles.export(scene.model, os.path.join(work, "export"))

    def _blender(self, args, timeout=None):
        cmd = ["blender", "-b", "--factory-startup", "--python-exit-code", "1", "--python", self.script, "--"] + args
        r, wall = run(cmd, timeout=timeout)
        lines = bench_lines(r.stdout)
        if r.returncode or not lines:
            raise RuntimeError(error_tail(r))
        return lines, wall

    def series(self, seed, spps):
        lines, wall = self._blender(["--spp-series", ",".join(map(str, spps)), "--seed", str(seed),
                                     "--out", self.out("series-%d-{spp}" % seed)])
        ref = read_rgb(self.scene.reference)
        points = [dict(spp=l["spp"], render_seconds=l["render_seconds"], relmse=relmse(read_rgb(l["out"]), ref))
                  for l in lines]
        return dict(points=points, setup_seconds=wall - sum(l["render_seconds"] for l in lines),
                    image=lines[-1]["out"], samples_per_second=self.scene.pixels * spps[-1] / lines[-1]["render_seconds"],
                    version=lines[-1]["blender"])

    def batches(self, seeds, spp):
        lines, wall = self._blender(["--spp", str(spp), "--seeds", ",".join(map(str, seeds)),
                                     "--out", self.out("ref-{seed}")])
        return [l["out"] for l in lines], wall

    def budget(self, seed, seconds):
        lines, wall = self._blender(["--time", str(seconds), "--seed", str(seed),
                                     "--out", self.out("budget-%g-%d" % (seconds, seed))])
        l = lines[-1]
        return dict(render_seconds=l["render_seconds"], setup_seconds=wall - l["render_seconds"], wall_seconds=wall,
                    relmse=relmse(read_rgb(l["out"]), read_rgb(self.scene.reference)))


def read_export_back(scene, xml, work, spp=64):
    """pathcl's importer reading the Mitsuba export: pathcl renders the exported XML (the file Mitsuba
    renders) and its image is compared with the reference of the pathcl scene. Where the two agree, the
    export is the scene pathcl renders, and a disagreement of Mitsuba's image is Mitsuba's; where they do
    not, the exporter or the importer is wrong, and the run stops before timing anything. Returns the
    per-channel ratio of the image means and the relMSE."""
    import numpy as np
    out = os.path.join(work, "export-read-back.exr")
    r, _ = run([PATHCL, "render", xml, "--spp", str(spp), "--seed", "7", "-q", "-o", out])
    if r.returncode != 0:
        raise RuntimeError("pathcl cannot read the export %s: %s" % (xml, error_tail(r)))
    image, ref = read_rgb(out), read_rgb(scene.reference)
    ratio = [float(image[c].mean() / ref[c].mean()) for c in range(3)]
    result = dict(spp=spp, mean_ratio=ratio, relmse=relmse(image, ref))
    if any(abs(x - 1) > 0.02 for x in ratio):
        raise RuntimeError("the export is another scene: pathcl renders it with channel means %s of the scene's "
                           "(%s)" % (" ".join("%.4f" % x for x in ratio), xml))
    return result


class PeerProcess(Renderer):
    """Mitsuba and LuxCore through peer_runners.py in a subprocess."""

    def __init__(self, name, scene, work):
        super().__init__(name, scene, work)
        self.peer, self.variant = name.split("-", 1)
        export_dir = os.path.join(work, "export")
        self.read_back = None
        if self.peer == "mitsuba":
            self.target = export_mitsuba.export(scene.model, export_dir)
            self.read_back = read_export_back(scene, self.target, work)
        else:
            export_luxcore.export(scene.model, export_dir, self.variant)
            self.target = export_dir
        self.env = dict(os.environ)
        if self.name == "mitsuba-llvm_ad_rgb":
            # Dr.Jit's JIT with the system's LLVM 15 aborts on this machine ("Cannot select ... fminimum");
            # it runs with LLVM 19 (Debian's libllvm19, installed by scripts/bench/peers).
            found = sorted(glob.glob("/usr/lib/*/libLLVM.so.19*") + glob.glob("/usr/lib/llvm-19/lib/libLLVM*.so*"))
            if found:
                self.env["DRJIT_LIBLLVM_PATH"] = found[0]
        if self.name == "luxcore-PATHOCL":
            # pyluxcore's wheel brings TBB's malloc proxy, which takes over malloc only once pyluxcore is
            # loaded: memory PoCL and LLVM allocated before is then freed by the other allocator ("double free
            # or corruption" while enumerating the PoCL device). Preloaded, it serves the process from the start.
            libs = sorted(glob.glob(os.path.join(sys.prefix, "lib", "python3*", "site-packages", "pyluxcore.libs",
                                                 "libtbbmalloc*.so*")), key=lambda p: "proxy" in p)  # allocator, proxy
            if libs:
                self.env["LD_PRELOAD"] = " ".join(libs)
        if self.name == "luxcore-PATHCPU":
            # pyluxcore 2.11 aborts ("double free or corruption") while enumerating PoCL's OpenCL device;
            # PATHCPU needs no OpenCL, so it runs with no OpenCL driver visible.
            os.makedirs(NO_ICD, exist_ok=True)
            self.env["OCL_ICD_VENDORS"] = NO_ICD

    def _run(self, args, timeout):
        cmd = [sys.executable, os.path.join(HERE, "peer_runners.py"), self.peer, self.variant, self.target] + args
        if AVX2 and self.peer == "mitsuba":
            cmd.append("--avx2")
        r, wall = run(cmd, env=self.env, timeout=timeout)
        lines = bench_lines(r.stdout)
        if r.returncode or not lines:
            raise RuntimeError(error_tail(r))
        return lines, wall

    def series(self, seed, spps):
        lines, wall = self._run(["--spp-series", ",".join(map(str, spps)), "--seed", str(seed),
                                 "--out", self.out("series-%d-{spp}" % seed)], timeout=3600)
        ref = read_rgb(self.scene.reference)
        points = [dict(spp=l["spp"], render_seconds=l["render_seconds"], relmse=relmse(read_rgb(l["out"]), ref))
                  for l in lines]
        last = points[-1]
        return dict(points=points, setup_seconds=lines[0]["setup_seconds"], image=lines[-1]["out"],
                    samples_per_second=self.scene.pixels * last["spp"] / last["render_seconds"],
                    version=lines[-1]["version"])

    def budget(self, seed, seconds):
        if self.peer == "mitsuba":
            raise RuntimeError(MITSUBA_TIMEOUT)
        key = "--timeout" if self.peer == "mitsuba" else "--time"
        # Mitsuba: a sample count it cannot reach, cut by the integrator's timeout.
        lines, wall = self._run(["--spp-series", "1048576" if self.peer == "mitsuba" else "1", "--seed", str(seed),
                                 key, str(seconds), "--out", self.out("budget-%g-%d" % (seconds, seed))],
                                timeout=seconds * 10 + 300)
        l = lines[-1]
        return dict(render_seconds=l["render_seconds"], setup_seconds=l["setup_seconds"], wall_seconds=wall,
                    spp=l.get("spp"), relmse=relmse(read_rgb(l["out"]), read_rgb(self.scene.reference)))


def make_renderer(name, scene, work):
    if name == "pathcl":
        return Pathcl(name, scene, work)
    if name == "cycles":
        return Cycles(name, scene, work)
    return PeerProcess(name, scene, work)


# --- analysis --------------------------------------------------------------------------------------

def median_points(series_runs):
    """Median render time and relMSE per spp over runs."""
    by_spp = {}
    for s in series_runs:
        for p in s["points"]:
            by_spp.setdefault(p["spp"], []).append(p)
    return [dict(spp=spp, render_seconds=statistics.median(p["render_seconds"] for p in ps),
                 relmse=statistics.median(p["relmse"] for p in ps), runs=len(ps))
            for spp, ps in sorted(by_spp.items())]


def error_curve(series_points, budgets):
    """relMSE against render seconds: the series' median points and each time budget's median render
    (render seconds, relMSE), in order of time. Budgets reach further than the series on slow scenes."""
    pts = [dict(render_seconds=p["render_seconds"], relmse=p["relmse"], source="%d spp" % p["spp"])
           for p in series_points]
    pts += [dict(render_seconds=b["render_seconds"], relmse=b["render_only_relmse"], source="budget")
            for b in budgets if b.get("render_seconds") and b.get("render_only_relmse")]
    return sorted(pts, key=lambda p: p["render_seconds"])


def time_to(points, target):
    """Render seconds to reach relMSE TARGET: log-log interpolation in the curve, else extrapolated from
    its last point with relMSE proportional to 1 / time. Returns (seconds, extrapolated)."""
    pts = [p for p in points if p["relmse"] > 0 and p["render_seconds"] > 0]
    for a, b in zip(pts, pts[1:]):
        if a["relmse"] >= target >= b["relmse"]:
            if a["relmse"] == b["relmse"]:
                return b["render_seconds"], False
            f = math.log(a["relmse"] / target) / math.log(a["relmse"] / b["relmse"])
            return math.exp(math.log(a["render_seconds"]) + f * math.log(b["render_seconds"] / a["render_seconds"])), False
    if pts and pts[0]["relmse"] <= target:
        return pts[0]["render_seconds"], False
    if not pts:
        return None, False
    last = pts[-1]
    return last["render_seconds"] * last["relmse"] / target, True


def relmse_at(points, seconds):
    """relMSE after SECONDS of rendering, from the series (log-log interpolation; relMSE ~ 1/t outside)."""
    pts = [p for p in points if p["relmse"] > 0 and p["render_seconds"] > 0]
    if not pts or seconds <= 0:
        return None
    if seconds <= pts[0]["render_seconds"]:
        return pts[0]["relmse"] * pts[0]["render_seconds"] / seconds
    for a, b in zip(pts, pts[1:]):
        if a["render_seconds"] <= seconds <= b["render_seconds"]:
            f = math.log(seconds / a["render_seconds"]) / math.log(b["render_seconds"] / a["render_seconds"])
            return math.exp(math.log(a["relmse"]) + f * math.log(b["relmse"] / a["relmse"]))
    return pts[-1]["relmse"] * pts[-1]["render_seconds"] / seconds


def reference_noise_relmse(ref, ref_var):
    """The reference's own expected relMSE against the true image, mean of var / (ref^2 + 0.01): a render's
    relMSE against the reference exceeds its relMSE against the true image by this much (independent noise)."""
    import numpy as np
    return float(np.mean(ref_var / (ref * ref + 0.01)))


def summarize(series_runs, budget_runs, noise):
    """One renderer's figures from its series runs and {budget seconds: [budget runs]}. relMSE figures are
    against the true image: relMSE against the reference minus NOISE (reference_noise_relmse)."""
    pts = [dict(p, relmse=p["relmse"] - noise, relmse_vs_reference=p["relmse"]) for p in median_points(series_runs)]
    setup = statistics.median(s["setup_seconds"] for s in series_runs)
    res = dict(series_runs=series_runs, median_points=pts, setup_seconds=setup, reference_noise_relmse=noise,
               samples_per_second=statistics.median(s["samples_per_second"] for s in series_runs), budgets={})
    for b, runs_b in sorted(budget_runs.items()):
        res["budgets"]["%g" % b] = dict(
            render_only_relmse=statistics.median(x["relmse"] for x in runs_b) - noise if runs_b else None,
            render_seconds=statistics.median(x["render_seconds"] for x in runs_b) if runs_b else None,
            wall_seconds=statistics.median(x["wall_seconds"] for x in runs_b) if runs_b else None,
            runs=runs_b)
    # The error curve: the series' points and the budget renders' (median time, median relMSE).
    curve = error_curve(pts, res["budgets"].values())
    res["error_curve"] = curve
    for b in budget_runs:
        res["budgets"]["%g" % b]["with_setup_relmse_from_series"] = relmse_at(curve, b - setup)
    for target in (1e-2, 1e-3):
        t, extrapolated = time_to(curve, target)
        res["time_to_%g" % target] = dict(render_seconds=t, with_setup_seconds=None if t is None else t + setup,
                                          extrapolated=extrapolated)
    return res


def rescore(path, work):
    """Recomputes a results file's figures (summarize) with the reference noise of the references that
    run left in WORK (for runs made before the noise correction)."""
    with open(path) as f:
        results = json.load(f)
    for scene_name, entry in results["scenes"].items():
        if not entry.get("renderers"):
            continue
        ref_path = os.path.join(work, os.path.splitext(os.path.basename(scene_name))[0], "reference.exr")
        ref, ref_var = read_rgb(ref_path, variance=True)
        noise = reference_noise_relmse(ref, ref_var)
        entry["reference"]["noise_relmse"] = noise
        for name, r in entry["renderers"].items():
            budget_runs = {float(b): v["runs"] for b, v in r["budgets"].items()}
            images = [s["image"] for s in r["series_runs"]]
            if all(map(os.path.exists, images)):
                agree = agreement(images, ref, noise)
            else:
                agree = r["agreement"]
                log("[%s] %s: the runs' images are gone, agreement kept as it was" % (scene_name, name))
            entry["renderers"][name] = dict(summarize(r["series_runs"], budget_runs, noise), agreement=agree)
        log("[%s] reference noise relMSE %.3g" % (scene_name, noise))
    results["rescored"] = "reference noise subtracted by peers.py --rescore"
    with open(path, "w") as f:
        json.dump(results, f, indent=1)


def agreement(images, reference, noise):
    """A renderer's mean image against the reference: per-channel relative difference of the image means
    and its z (standard error from the per-pixel spread of the difference), and the relMSE floor (the
    part more samples would not remove) from S runs: (S relMSE(mean image) - mean relMSE) / (S - 1), both
    against the true image: NOISE, the reference's own (reference_noise_relmse), subtracted."""
    import numpy as np
    xs = [read_rgb(p) for p in images]
    mean = np.mean(xs, axis=0)
    d = (mean - reference).reshape(3, -1)
    se = d.std(axis=1, ddof=1) / math.sqrt(d.shape[1])
    ref_mean = reference.reshape(3, -1).mean(axis=1)
    out = dict(runs=len(xs), relative_mean_difference=(d.mean(axis=1) / ref_mean).tolist(),
               mean_difference_z=(d.mean(axis=1) / se).tolist())
    # Both relMSEs carry the reference's own noise once (the floor formula keeps it whole): subtracted, the
    # floor is the renderer's bias against the true image, not the reference's noise.
    per_run = float(np.mean([relmse(x, reference) for x in xs]))
    out["relmse_per_run"] = per_run - noise
    if len(xs) > 1:
        out["relmse_floor"] = (len(xs) * relmse(mean, reference) - per_run) / (len(xs) - 1) - noise
    return out


def reference_ztest(ref, ref_var, cycles_images):
    """Per-pixel z-test of the pathcl reference against the mean of K Cycles renders (variance of that
    mean from their spread, K - 1 degrees of freedom); a pixel fails if any channel has |z| above the
    Student-t quantile for two-sided p = 0.001."""
    import numpy as np
    from scipy import stats
    xs = np.array([read_rgb(p) for p in cycles_images])
    k = len(xs)
    c_mean, c_var = xs.mean(axis=0), xs.var(axis=0, ddof=1) / k
    var = ref_var + c_var
    threshold = float(stats.t.ppf(1 - 0.0005, k - 1))
    with np.errstate(divide="ignore", invalid="ignore"):
        z = np.abs(ref - c_mean) / np.sqrt(var)
    z = np.where(var > 0, z, np.where(ref == c_mean, 0, np.inf))
    fail = (z > threshold).any(axis=0)
    return dict(pass_fraction=float(1 - fail.mean()), threshold=threshold, cycles_renders=k,
                pixels=int(fail.size), accepted=bool(1 - fail.mean() >= 0.99),
                relmse_cycles_mean_vs_reference=relmse(c_mean, ref),
                mean_reference=ref.reshape(3, -1).mean(axis=1).tolist(),
                mean_cycles=c_mean.reshape(3, -1).mean(axis=1).tolist())


# --- traversal -------------------------------------------------------------------------------------

def rays_benchmark(scene, work, runs):
    os.makedirs(work, exist_ok=True)
    cam, cam_hits, bounce, bounce_hits = (os.path.join(work, n) for n in ("camera.rays", "camera.hits", "bounce.rays",
                                                                         "bounce.hits"))
    for cmd in ([MAKE_RAYS, "camera", scene.json, cam, "2"],
                [PATHCL, "rays", scene.json, "--rays", cam, "--hits", cam_hits, "--repeat", "1"],
                [MAKE_RAYS, "bounce", scene.json, cam, cam_hits, bounce],
                [PATHCL, "rays", scene.json, "--rays", bounce, "--hits", bounce_hits, "--repeat", "1"]):
        r, _ = run(cmd)
        if r.returncode:
            raise RuntimeError(" ".join(cmd) + ": " + error_tail(r))
    out = {}
    for name, rays, hits in (("camera", cam, cam_hits), ("diffuse_bounce", bounce, bounce_hits)):
        res = {"pathcl": [], "embree-1": [], "embree-2": []}
        for _ in range(runs):  # A B C A B C
            stats = os.path.join(work, "rays-stats.json")
            r, _ = run([PATHCL, "rays", scene.json, "--rays", rays, "--repeat", "5", "--stats", stats])
            if r.returncode:
                raise RuntimeError(error_tail(r))
            with open(stats) as f:
                s = json.load(f)
            res["pathcl"].append(dict(rays_per_second=s["rays_per_second_kernel"],
                                      rays_per_second_wall=s["rays_per_second_wall"], rays=s["rays"], hits=s["hits"]))
            for threads in (1, 2):
                r, _ = run([EMBREE_RAYS, scene.dump, rays, "--threads", str(threads), "--repeat", "5", "--compare", hits]
                           + (["--isa", "avx2"] if AVX2 else []))
                if r.returncode:
                    raise RuntimeError(error_tail(r))
                res["embree-%d" % threads].append(json.loads(r.stdout))
        out[name] = {k: dict(rays_per_second=statistics.median(x["rays_per_second"] for x in v), runs=v)
                     for k, v in res.items()}
        out[name]["embree_same_primitive_fraction"] = res["embree-2"][0]["same_primitive_fraction"]
        out[name]["embree_t_within_1e-4_fraction"] = res["embree-2"][0]["t_within_1e-4_fraction"]
        out[name]["rays"] = res["pathcl"][0]["rays"]
        out[name]["embree_build_ms"] = statistics.median(x["build_ms"] for x in res["embree-1"])
    return out


# --- main ------------------------------------------------------------------------------------------

class SceneInfo:
    pass


SCENES = {"cornell": "cornell-official.json", "glass-metal": "glass-metal.json"}  # in scenes/


def scene_paths(name, data_dir):
    if name in SCENES:
        if name == "glass-metal" and not os.path.exists(scene_model.ICOSPHERE_MESH):
            scene_model.write_icosphere_obj()  # the generated mesh the scene's spheres use
        return os.path.join(ROOT, "scenes", SCENES[name])
    if name == "terrain":
        path = os.path.join(data_dir, "terrain.json")
        if not os.path.exists(path):
            subprocess.run([sys.executable, os.path.join(ROOT, "scripts", "make-bench-scene"), data_dir], check=True)
        return path
    return os.path.abspath(name)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenes", default="cornell,glass-metal,terrain",
                    help="cornell, glass-metal, terrain or scene JSON paths")
    ap.add_argument("--renderers", default=",".join(RENDERERS))
    ap.add_argument("--budgets", default="5,30,120", help="render time budgets in seconds")
    ap.add_argument("--runs", type=int, default=3, help="runs per figure (medians are reported)")
    ap.add_argument("--series", default="1,4,16,64,256", help="spp of the convergence series")
    ap.add_argument("--ref-spp", type=int, default=4096, help="pathcl reference spp")
    ap.add_argument("--ref-cycles-spp", type=int, default=256, help="spp of each Cycles reference render")
    ap.add_argument("--ref-cycles-batches", type=int, default=8, help="Cycles reference renders (seeds)")
    ap.add_argument("--rays", default="terrain", help="scenes for the traversal benchmark ('' for none)")
    ap.add_argument("--work", default=os.path.join(ROOT, "bench", "out", "peers"))
    ap.add_argument("--results", help="JSON to write (default bench/results/<date>T<hhmm>-<machine>.json; a run of"
                    " some renderers only belongs in bench/results/supplementary/)")
    ap.add_argument("--no-docs", action="store_true", help="do not regenerate docs/benchmarks.md")
    ap.add_argument("--avx2", action="store_true", help="AVX2 code for pathcl, Mitsuba's LLVM variants and Embree"
                    " (scripts/bench/avx2.py)")
    ap.add_argument("--rescore", metavar="RESULTS", help="only recompute RESULTS' figures against the true image"
                    " (the reference noise from the references in --work) and regenerate the docs")
    args = ap.parse_args()
    if args.rescore:
        rescore(args.rescore, args.work)
        if not args.no_docs:
            import report
            report.write_all()
        return

    os.environ.setdefault("PATHCL_KERNEL_CACHE", os.path.join(ROOT, "build", "kernel-cache"))
    global AVX2
    AVX2 = args.avx2
    if AVX2:
        os.environ.update(AVX2_ENV)
    renderers = [r for r in args.renderers.split(",") if r]
    budgets = [float(b) for b in args.budgets.split(",") if b]
    spps = [int(s) for s in args.series.split(",")]
    machine = platform.node() or "machine"
    results = dict(date=datetime.datetime.now().isoformat(timespec="seconds"), machine=machine,
                   cpu=_cpu_name(), cores=os.cpu_count(), command=" ".join(sys.argv), settings=vars(args),
                   scenes={})
    started = time.time()
    data_dir = os.path.join(ROOT, "bench", "data")
    render_scenes = [s for s in args.scenes.split(",") if s]
    ray_scenes = [s for s in args.rays.split(",") if s]
    for scene_name in render_scenes + [s for s in ray_scenes if s not in render_scenes]:
        sc = SceneInfo()
        sc.name, sc.json = scene_name, scene_paths(scene_name, data_dir)
        # A scene given as a path works in a directory named after its file.
        work = os.path.join(args.work, os.path.splitext(os.path.basename(scene_name))[0])
        os.makedirs(work, exist_ok=True)
        sc.dump = os.path.join(work, "scene.obj")
        scene_model.dump_scene_obj(PATHCL, sc.json, sc.dump)
        sc.model = scene_model.load(sc.json, sc.dump)
        sc.pixels = sc.model.camera.width * sc.model.camera.height
        entry = dict(json=os.path.relpath(sc.json, ROOT), triangles=sc.model.triangle_count(),
                     width=sc.model.camera.width, height=sc.model.camera.height, max_depth=sc.model.max_depth,
                     renderers={}, errors={})
        results["scenes"][scene_name] = entry
        if scene_name not in render_scenes:  # traversal only
            log("[%s] traversal: pathcl rays vs Embree" % scene_name)
            try:
                entry["rays"] = rays_benchmark(sc, os.path.join(work, "rays"), args.runs)
            except Exception as e:  # noqa: BLE001
                entry["errors"]["rays"] = str(e)
            continue

        # pathcl kernel build, cold (both caches off) and cached.
        cold_cache = os.path.join(work, "cold-kernel-cache")
        shutil.rmtree(cold_cache, ignore_errors=True)
        env = dict(os.environ, PATHCL_KERNEL_CACHE=cold_cache, POCL_KERNEL_CACHE="0")
        builds = []
        for _ in range(2):
            st = os.path.join(work, "build-stats.json")
            r, _ = run([PATHCL, "render", sc.json, "--spp", "1", "-q", "-o", os.path.join(work, "b.exr"), "--stats", st],
                       env=env)
            with open(st) as f:
                builds.append(json.load(f))
        entry["pathcl_build"] = dict(kernel_build_ms_cold=builds[0]["kernel_build_ms"],
                                     kernel_build_ms_cached=builds[1]["kernel_build_ms"],
                                     bvh_build_ms=builds[0]["bvh_build_ms"], scene_load_ms=builds[0]["scene_load_ms"],
                                     kernel_options=builds[0].get("kernel_options"), device=builds[0]["device"])

        # Reference and its acceptance against Cycles.
        sc.reference = os.path.join(work, "reference.exr")
        log("[%s] reference: pathcl %d spp" % (scene_name, args.ref_spp))
        st = os.path.join(work, "reference.json")
        # Independent samples: their per-pixel variance is the reference's true error, as the z-tests need
        # (a low-discrepancy sampler's variance overstates it and would make the tests lenient).
        r, wall = run([PATHCL, "render", sc.json, "--spp", str(args.ref_spp), "--variance", "--seed", "1000", "-q",
                       "--sampler", "independent", "-o", sc.reference, "--stats", st])
        if r.returncode:
            raise SystemExit("reference render failed: " + error_tail(r))
        ref, ref_var = read_rgb(sc.reference, variance=True)
        entry["reference"] = dict(spp=args.ref_spp, seconds=wall)
        if args.ref_cycles_batches > 1:
            log("[%s] reference check: Cycles %d x %d spp" % (scene_name, args.ref_cycles_batches, args.ref_cycles_spp))
            try:
                cy = Cycles("cycles", sc, os.path.join(work, "cycles-reference"))
                images, wall = cy.batches(list(range(101, 101 + args.ref_cycles_batches)), args.ref_cycles_spp)
                entry["reference"]["cycles_check"] = dict(reference_ztest(ref, ref_var, images),
                                                          spp_each=args.ref_cycles_spp, seconds=wall)
            except Exception as e:  # noqa: BLE001
                entry["reference"]["cycles_check"] = dict(error=str(e))
            log("[%s] reference z-test: %s" % (scene_name, entry["reference"]["cycles_check"]))

        active = {}
        for name in renderers:
            try:
                active[name] = make_renderer(name, sc, os.path.join(work, name))
            except Exception as e:  # noqa: BLE001
                entry["errors"][name] = "export: %s" % e
        series = {n: [] for n in active}
        budget = {n: {b: [] for b in budgets} for n in active}
        for run_index in range(args.runs):
            seed = run_index + 1
            for name, rend in list(active.items()):  # A B C ... A B C ...
                if name in entry["errors"]:
                    continue
                log("[%s] run %d: %s series %s" % (scene_name, seed, name, args.series))
                try:
                    series[name].append(rend.series(seed, spps))
                except Exception as e:  # noqa: BLE001
                    entry["errors"][name] = str(e)
                    log("  failed: %s" % e)
                    continue
                for b in budgets:
                    log("[%s] run %d: %s budget %g s" % (scene_name, seed, name, b))
                    try:
                        budget[name][b].append(rend.budget(seed, b))
                    except Exception as e:  # noqa: BLE001
                        entry["errors"].setdefault(name + " budget", str(e))
        noise = reference_noise_relmse(ref, ref_var)
        entry["reference"]["noise_relmse"] = noise
        for name in active:
            if not series[name]:
                continue
            res = summarize(series[name], budget[name], noise)
            res["agreement"] = agreement([s["image"] for s in series[name]], ref, noise)
            if getattr(active[name], "read_back", None):
                res["pathcl_reads_export"] = active[name].read_back
            entry["renderers"][name] = res
        if scene_name in ray_scenes:
            log("[%s] traversal: pathcl rays vs Embree" % scene_name)
            try:
                entry["rays"] = rays_benchmark(sc, os.path.join(work, "rays"), args.runs)
            except Exception as e:  # noqa: BLE001
                entry["errors"]["rays"] = str(e)
    results["wall_seconds"] = time.time() - started

    # One file per run (date and time of day): docs/benchmarks.md takes each scene from the newest run.
    path = args.results or os.path.join(ROOT, "bench", "results", "%s-%s.json" % (
        datetime.datetime.now().strftime("%Y-%m-%dT%H%M"), machine))
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "w") as f:
        json.dump(results, f, indent=1)
    log("results: " + os.path.relpath(path, ROOT))
    if not args.no_docs:
        import report
        report.write_all()


def _cpu_name():
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor()


if __name__ == "__main__":
    main()
