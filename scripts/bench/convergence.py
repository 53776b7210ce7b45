"""What the speed-against-error benchmarks of estimators share (scripts/bench/merging, scripts/bench/estimators):
a reference's own noise, and a render's relMSE against it at each power of two spp with the time it took."""
import csv
import json
import os
import subprocess
import sys

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
OUT = os.path.join(ROOT, "bench", "out")
PATHCL = os.path.join(ROOT, "build", "pathcl")
TARGETS = (1e-2, 1e-3)


def exr_noise(path):
    """Mean over pixels and channels of variance / (mean^2 + 0.01) of an EXR written with --variance, and the
    image's mean."""
    try:
        import OpenEXR
    except ImportError:
        subprocess.run([sys.executable, "-m", "pip", "install", "-q", "OpenEXR"], check=True)
        import OpenEXR
    with OpenEXR.File(path) as f:
        ch = f.channels()
        rgb, var = ch["RGB"].pixels.astype("float64"), ch["variance"].pixels.astype("float64")
    return float((var / (rgb * rgb + 0.01)).mean()), float(rgb.mean())


def run(cmd, device):
    subprocess.run(cmd + (["--device", device] if device else []), check=True)


def render(scene, integrator, device, ref, ref_noise, ref_mean, max_spp, seed, tag):
    """Renders `scene` to max_spp with --convergence against `ref`: per power of two spp its time (kernel
    build and scene load excluded), relMSE less the reference's own noise and image mean's error; the time to
    each target (the first row below it, None if none)."""
    stats, image, rows = (os.path.join(OUT, f"{tag}-run.{x}") for x in ("json", "exr", "csv"))
    run([PATHCL, "render", scene, "--integrator", integrator, "--spp", str(max_spp), "--quiet", "--seed", str(seed),
         "-o", image, "--stats", stats, "--reference", ref, "--convergence", rows], device)
    with open(stats) as f:
        s = json.load(f)
    with open(rows) as f:
        table = list(csv.DictReader(f))
    out = {"spp": s["spp"], "seconds": s["render_seconds"], "kernel_build_ms": s["kernel_build_ms"],
           "buffer_bytes": s["devices"][0].get("buffer_bytes", {}), "phases": s.get("phases", {}), "rows": []}
    for row in table:
        relmse = float(row["relmse"]) - ref_noise
        mean_error = None
        if "mean" in row and ref_mean > 0:
            mean_error = float(row["mean"]) / ref_mean - 1
        out["rows"].append({"spp": int(row["spp"]), "seconds": float(row["render_seconds"]), "relmse": relmse, "mean_error": mean_error})
    for t in TARGETS:
        hit = next((r for r in out["rows"] if r["relmse"] < t), None)
        out[f"time_to_{t:g}"] = hit["seconds"] if hit else None
    return out
