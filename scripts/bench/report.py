#!/usr/bin/env python3
"""Writes docs/benchmarks.md and its log-log plots from a scripts/bench/peers results JSON.

Usage: scripts/bench/report.py [RESULTS.json ... [docs/benchmarks.md]]   (needs numpy and matplotlib: the
bench venv). Without arguments: every file in bench/results/ (and bench/results/supplementary/, runs of some
renderers only, in a section of their own). Each scene is reported from the newest results file that has it, so a run of
one scene does not drop the others. The hand-written analysis lives in docs/benchmarks-notes.md and is
appended verbatim.
"""
import json
import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def fmt(x, spec="%.3g"):
    return "–" if x is None else spec % x


def plot(scene_name, entry, png):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for i, (name, r) in enumerate(sorted(entry["renderers"].items())):
        pts = r["median_points"]
        colour = "C%d" % i
        ax.loglog([p["render_seconds"] for p in pts], [p["relmse"] for p in pts], "o-", color=colour,
                  label="%s (render time)" % name)
        ax.loglog([p["render_seconds"] + r["setup_seconds"] for p in pts], [p["relmse"] for p in pts], ":",
                  color=colour, alpha=0.6)
        for b, v in r["budgets"].items():
            if v["render_only_relmse"] is not None:
                ax.loglog([v["render_seconds"]], [v["render_only_relmse"]], "x", color=colour, ms=9)
    for target in (1e-2, 1e-3):
        ax.axhline(target, color="grey", lw=0.8, ls="--")
    ax.set_xlabel("seconds (solid: render time; dotted: set-up + render; x: time-budget runs)")
    ax.set_ylabel("relMSE against the reference (median of runs)")
    ax.set_title("%s: %d triangles, %dx%d, max_depth %d" % (scene_name, entry["triangles"], entry["width"],
                                                          entry["height"], entry["max_depth"]))
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(png, dpi=80)
    plt.close(fig)


def latest_per_scene(results_paths):
    """{scene: [(run, entry, path), ...]}: the renders from the newest run (by its date) that rendered the scene,
    then the traversal figures from the newest run that traced its rays (the same run or another). Each
    entry keeps only its part, so one run's renders are not shown with another's ray figures as one run."""
    runs = []
    for path in results_paths:
        with open(path) as f:
            runs.append((json.load(f), path))
    parts = {}
    for run, path in sorted(runs, key=lambda rp: rp[0]["date"]):
        for name, entry in run["scenes"].items():
            for part, has in (("renders", bool(entry.get("renderers"))), ("rays", bool(entry.get("rays")))):
                if has:
                    parts.setdefault(name, {})[part] = (run, entry, path)
    scenes = {}
    for name, p in parts.items():
        if len(p) == 2 and p["renders"][2] == p["rays"][2]:  # both from one run
            scenes[name] = [p["renders"]]
            continue
        scenes[name] = []
        for part, (run, entry, path) in sorted(p.items(), key=lambda kv: kv[0] != "renders"):
            errors = {k: v for k, v in entry.get("errors", {}).items() if (k == "rays") == (part == "rays")}
            only = dict(entry, rays=None, errors=errors) if part == "renders" else dict(entry, renderers={}, errors=errors)
            scenes[name].append((run, only, path))
    return scenes


def scene_section(scene_name, picks, img_dir, png_tag=""):
    """Markdown lines for one scene: [(run, entry, path)] as latest_per_scene gives them."""
    out = ["## %s" % scene_name, ""] if not png_tag else ["### %s" % scene_name, ""]
    for res, e, path in picks:
        out += ["Run of %s on %s (%d cores), `%s`: `%s`" % (res["date"], res["cpu"], res["cores"],
                                                             os.path.relpath(path, ROOT), res["command"]), ""]
        if "renderers" in e and e["renderers"]:
            out += ["`%s`: %d triangles, %d×%d pixels, pathcl max_depth %d." % (e["json"], e["triangles"], e["width"],
                                                                               e["height"], e["max_depth"]), ""]
            ref = e.get("reference", {})
            chk = ref.get("cycles_check", {})
            out += ["**Reference**: pathcl, %s spp (%.0f s)." % (ref.get("spp"), ref.get("seconds", 0))]
            if "noise_relmse" in ref:
                out += ["Its own noise, mean of variance / (ref² + 0.01) = %.3g, is subtracted from every relMSE"
                        " below, so they estimate the error against the true image (a render's relMSE against a"
                        " noisy reference is its true relMSE plus the reference's)." % ref["noise_relmse"]]
            if "pass_fraction" in chk:
                out += ["Per-pixel z-test against the mean of %d Cycles renders of %d spp (|z| threshold %.2f, Student t"
                        " with %d degrees of freedom, two-sided p = 0.001, a pixel fails if any channel does): **%.2f %%**"
                        " of %d pixels pass (%s; ≥ 99 %% required). Image means: pathcl %s, Cycles %s."
                        % (chk["cycles_renders"], chk["spp_each"], chk["threshold"], chk["cycles_renders"] - 1,
                           100 * chk["pass_fraction"], chk["pixels"], "accepted" if chk["accepted"] else "NOT accepted",
                           ", ".join("%.5f" % x for x in chk["mean_reference"]),
                           ", ".join("%.5f" % x for x in chk["mean_cycles"]))]
            elif chk:
                out += ["Cycles check failed: `%s`" % chk.get("error")]
            out += [""]
            b = e.get("pathcl_build", {})
            if b:
                out += ["pathcl set-up: kernel build %.0f ms cold (pathcl's and PoCL's caches off), %.0f ms from the cache;"
                        " BVH build %.2f ms; scene load and clean-up %.1f ms; device %s." %
                        (b["kernel_build_ms_cold"], b["kernel_build_ms_cached"], b["bvh_build_ms"], b["scene_load_ms"],
                         b["device"]), ""]
            budgets = sorted({k for r in e["renderers"].values() for k in r["budgets"]}, key=float)
            head = ["renderer", "samples/s", "set-up s", "time to 1e-2 (s)", "time to 1e-3 (s)"]
            head += ["relMSE @ %s s render" % k for k in budgets] + ["relMSE @ %s s incl. set-up" % k for k in budgets]
            out += ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
            for name, r in sorted(e["renderers"].items()):
                row = [name, "%.0f" % r["samples_per_second"], "%.2f" % r["setup_seconds"]]
                for t in ("1e-02", "0.001"):
                    v = r["time_to_%s" % ("0.01" if t == "1e-02" else t)]
                    row.append(fmt(v["render_seconds"], "%.2f") + (" (extrap.)" if v["extrapolated"] else ""))
                row += [fmt(r["budgets"][k]["render_only_relmse"], "%.3g") for k in budgets]
                row += [fmt(r["budgets"][k]["with_setup_relmse_from_series"], "%.3g") for k in budgets]
                out.append("| " + " | ".join(row) + " |")
            out += ["",
                    "Time to an error is the render time at which the error curve crosses it, interpolated log-log:"
                    " the curve is the median convergence series (spp %s) and the median time-budget renders, in order"
                    " of time; \"extrap.\" extends its last point with relMSE ∝ 1/time. \"render\" budgets"
                    " are separate runs with each renderer's own time limit (pathcl `--time`, Cycles `time_limit`,"
                    " Mitsuba `timeout`, LuxCore `batch.halttime`); \"incl. set-up\" reads the series at budget − set-up"
                    " time. Set-up: pathcl scene load + BVH + kernel build (cached kernel); Cycles: Blender start, scene"
                    " build and sync (process wall time minus render time); Mitsuba: Python start and scene load;"
                    " LuxCore: Python start and session start." % res["settings"]["series"], ""]
            png = "benchmarks-%s%s.png" % (scene_name, png_tag)
            plot(scene_name, e, os.path.join(img_dir, png))
            out += ["![relMSE against time, %s](img/%s)" % (scene_name, png), ""]
            out += ["**Mean image against the reference** (each renderer's final series images, averaged over runs):",
                    "", "| renderer | relative mean difference R, G, B | z of the difference R, G, B | relMSE floor / per-run relMSE |",
                    "|---|---|---|---|"]
            for name, r in sorted(e["renderers"].items()):
                a = r["agreement"]
                floor = a.get("relmse_floor")
                out.append("| %s | %s | %s | %s |" % (
                    name, ", ".join("%+.2e" % x for x in a["relative_mean_difference"]),
                    ", ".join("%+.2f" % x for x in a["mean_difference_z"]),
                    "–" if floor is None else "%.3f" % (floor / a["relmse_per_run"])))
            out += ["",
                    "The floor is the part of relMSE that more samples would not remove, from the runs' images"
                    " (as in docs/accuracy.md): (S·relMSE(mean image) − mean relMSE) / (S − 1); near 0 means the"
                    " renderer converges to the reference, near 1 that its error is all bias.", ""]
        if e.get("rays"):
            out += ["**Traversal** (%s, %d triangles; rays/s, median of %d runs × 5 repetitions; pathcl: kernel time on"
                    " the PoCL device with both cores; Embree: rtcIntersect1, 1 and 2 threads):" % (
                        e["json"], e["triangles"], len(next(iter(e["rays"].values()))["pathcl"]["runs"])), "",
                    "| rays | count | pathcl | Embree 1 thread | Embree 2 threads | pathcl / Embree 2 | same primitive as pathcl |",
                    "|---|---|---|---|---|---|---|"]
            for name, r in e["rays"].items():
                p, e1, e2 = (r[k]["rays_per_second"] for k in ("pathcl", "embree-1", "embree-2"))
                out.append("| %s | %d | %.2f M | %.2f M | %.2f M | %.2f | %.6f |" % (
                    name, r["rays"], p / 1e6, e1 / 1e6, e2 / 1e6, p / e2, r["embree_same_primitive_fraction"]))
            out += [""]
        if e.get("errors"):
            out += ["**Could not run here** (exact errors):", ""]
            out += ["- `%s`: `%s`" % (k, v.replace("`", "'")[:600]) for k, v in e["errors"].items()]
            out += [""]
    return out


def write(results_paths, md_path, supplementary=()):
    if isinstance(results_paths, str):
        results_paths = [results_paths]
    scenes = latest_per_scene(results_paths)
    img_dir = os.path.join(os.path.dirname(md_path), "img")
    os.makedirs(img_dir, exist_ok=True)
    out = ["# Benchmarks against the peers",
           "",
           "Generated by `scripts/bench/report.py` from the results files in `bench/results/` (`scripts/bench/peers`"
           " writes one per run and regenerates this page), each scene from the newest run that has it; the"
           " analysis at the end is `docs/benchmarks-notes.md`. Each run names its machine; runs on different"
           " machines are not comparable with each other, renderers within one run are.",
           "",
           "relMSE = mean over pixels and channels of (x − ref)² / (ref² + 0.01), as `pathcl compare`. Figures are"
           " medians over the runs; the renderers ran one after another in A B C … A B C … order.",
           ""]
    for scene_name, picks in scenes.items():
        out += scene_section(scene_name, picks, img_dir)
    if supplementary:
        out += ["## Supplementary runs", "",
                "Runs of some renderers only (bench/results/supplementary/), each with pathcl in the same run as"
                " the anchor; they are not part of the tables above.", ""]
        for path in supplementary:
            for scene_name, picks in latest_per_scene([path]).items():
                tag = "-" + os.path.splitext(os.path.basename(path))[0]
                out += scene_section(scene_name, picks, img_dir, tag)
    notes = os.path.join(os.path.dirname(md_path), "benchmarks-notes.md")
    if os.path.exists(notes):
        with open(notes) as f:
            out += [f.read()]
    with open(md_path, "w") as f:
        f.write("\n".join(out) + "\n")


def write_all(md_path=os.path.join(ROOT, "docs", "benchmarks.md"), results_dir=os.path.join(ROOT, "bench", "results")):
    """docs/benchmarks.md from every results file: bench/results/*.json for the main tables,
    bench/results/supplementary/*.json for the supplementary section."""
    def jsons(d):
        return sorted(os.path.join(d, f) for f in os.listdir(d) if f.endswith(".json")) if os.path.isdir(d) else []
    write(jsons(results_dir), md_path, jsons(os.path.join(results_dir, "supplementary")))


if __name__ == "__main__":
    args = sys.argv[1:]
    if not args:
        write_all()
    else:
        md = args.pop() if args[-1].endswith(".md") else os.path.join(ROOT, "docs", "benchmarks.md")
        write(args, md)
