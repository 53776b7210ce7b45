"""report.py's choice of runs (each scene from the newest results file that has it) and peers.py's error curve
and times to an error (standard library only)."""
import json
import math
import os
import tempfile
import unittest

import peers
import report


class LatestPerSceneTest(unittest.TestCase):
    def scenes_of(self, runs):
        with tempfile.TemporaryDirectory() as tmp:
            paths = []
            for name, run in runs.items():
                paths.append(os.path.join(tmp, name))
                with open(paths[-1], "w") as f:
                    json.dump(run, f)
            scenes = report.latest_per_scene(paths)
        return {k: [(e.get("v"), sorted(x for x in ("renderers", "rays") if e.get(x)), os.path.basename(p))
                    for _, e, p in picks] for k, picks in scenes.items()}

    def test_each_scene_comes_from_the_newest_run_that_has_it(self):
        r = {"renderers": {"pathcl": {}}}
        runs = {"old.json": {"date": "2026-11-23T14:34:15", "scenes": {"cornell": dict(r, v=1), "fog": dict(r, v=2)}},
                "new.json": {"date": "2026-11-23T18:40:00", "scenes": {"glass": dict(r, v=3), "cornell": dict(r, v=4)}},
                "mid.json": {"date": "2026-11-23T16:00:00", "scenes": {"cornell": dict(r, v=5)}}}
        self.assertEqual(self.scenes_of(runs), {"cornell": [(4, ["renderers"], "new.json")],
                                                "fog": [(2, ["renderers"], "old.json")],
                                                "glass": [(3, ["renderers"], "new.json")]})

    def test_renders_and_rays_of_a_scene_come_from_the_newest_run_of_each(self):
        runs = {"a.json": {"date": "2026-11-23T14:00:00", "scenes": {"terrain": {"v": 1, "renderers": {"x": {}},
                                                                                 "rays": {"camera": {}}}}},
                "b.json": {"date": "2026-11-23T18:41:00", "scenes": {"terrain": {"v": 2, "rays": {"camera": {}}}}},
                "c.json": {"date": "2026-11-23T19:09:00", "scenes": {"terrain": {"v": 3, "renderers": {"x": {}}}}}}
        self.assertEqual(self.scenes_of(runs), {"terrain": [(3, ["renderers"], "c.json"), (2, ["rays"], "b.json")]})
        del runs["c.json"]  # renders from a, rays from b
        self.assertEqual(self.scenes_of(runs), {"terrain": [(1, ["renderers"], "a.json"), (2, ["rays"], "b.json")]})
        del runs["b.json"]  # both parts from one run: shown once, whole
        self.assertEqual(self.scenes_of(runs), {"terrain": [(1, ["rays", "renderers"], "a.json")]})


class ErrorCurveTest(unittest.TestCase):
    SERIES = [dict(spp=1, render_seconds=0.1, relmse=0.4), dict(spp=4, render_seconds=0.4, relmse=0.1),
              dict(spp=16, render_seconds=1.6, relmse=0.025)]

    def test_budget_renders_extend_the_series_in_order_of_time(self):
        budgets = [dict(render_seconds=5.0, render_only_relmse=0.008), dict(render_seconds=30.0, render_only_relmse=0.0013),
                   dict(render_seconds=None, render_only_relmse=None)]  # a renderer without budget runs
        curve = peers.error_curve(self.SERIES, budgets)
        self.assertEqual([p["render_seconds"] for p in curve], [0.1, 0.4, 1.6, 5.0, 30.0])
        self.assertEqual([p["source"] for p in curve], ["1 spp", "4 spp", "16 spp", "budget", "budget"])
        # 1e-2 lies between 1.6 s (0.025) and 5 s (0.008): interpolated log-log, not extrapolated
        t, extrapolated = peers.time_to(curve, 1e-2)
        self.assertFalse(extrapolated)
        f = math.log(0.025 / 1e-2) / math.log(0.025 / 0.008)
        self.assertAlmostEqual(t, math.exp(math.log(1.6) + f * math.log(5.0 / 1.6)))
        # 1e-3 is past the last point: relMSE proportional to 1 / time from it
        t, extrapolated = peers.time_to(curve, 1e-3)
        self.assertTrue(extrapolated)
        self.assertAlmostEqual(t, 30.0 * 1.3)

    def test_series_alone_extrapolates_where_budgets_would_have_measured(self):
        t, extrapolated = peers.time_to(peers.error_curve(self.SERIES, []), 1e-2)
        self.assertTrue(extrapolated)
        self.assertAlmostEqual(t, 1.6 * 2.5)

    def test_summarize_subtracts_the_reference_noise_from_every_relmse(self):
        series = [dict(setup_seconds=1.0, samples_per_second=10.0,
                       points=[dict(p, relmse=p["relmse"] + 0.002) for p in self.SERIES])]
        budget = {5.0: [dict(render_seconds=5.0, relmse=0.010, wall_seconds=6.0)], 30.0: []}
        r = peers.summarize(series, budget, 0.002)
        self.assertEqual([p["relmse"] for p in r["median_points"]], [0.4, 0.1, 0.025])
        self.assertAlmostEqual(r["budgets"]["5"]["render_only_relmse"], 0.008)
        self.assertIsNone(r["budgets"]["30"]["render_only_relmse"])
        self.assertFalse(r["time_to_0.01"]["extrapolated"])  # reached by the 5 s budget render
        self.assertAlmostEqual(r["time_to_0.01"]["with_setup_seconds"], r["time_to_0.01"]["render_seconds"] + 1.0)


class AgreementTest(unittest.TestCase):
    """The relMSE floor and per-run relMSE are against the true image: the reference's own noise is removed."""

    def setUp(self):
        import numpy as np
        rng = np.random.default_rng(7)
        self.np, self.rng, self.dir = np, rng, tempfile.TemporaryDirectory()
        self.truth = rng.uniform(0.2, 1.0, (3, 64, 64))
        self.ref_var = np.full_like(self.truth, 0.01 ** 2)  # the reference's per-pixel variance
        self.reference = self.truth + rng.normal(0.0, 0.01, self.truth.shape)
        self.noise = peers.reference_noise_relmse(self.reference, self.ref_var)

    def tearDown(self):
        self.dir.cleanup()

    def renders(self, bias, sigma=0.02, runs=4):
        paths = []
        for i in range(runs):
            image = self.truth * (1 + bias) + self.rng.normal(0.0, sigma, self.truth.shape)
            paths.append(os.path.join(self.dir.name, "run%d-%g.npy" % (i, bias)))
            self.np.save(paths[-1], image.transpose(1, 2, 0))  # LuxCore's snapshot layout
        return paths

    def expected_relmse(self, var):
        return float(self.np.mean(var / (self.reference ** 2 + 0.01)))

    def test_unbiased_renders_have_no_floor_beyond_its_standard_error(self):
        self.assertAlmostEqual(self.noise, self.expected_relmse(self.ref_var), places=12)
        a = peers.agreement(self.renders(0.0), self.reference, self.noise)
        # per-run relMSE against the truth: the renders' own noise, sigma^2 weighted (relative s.e. 1/sqrt(N))
        own = self.expected_relmse(self.np.full_like(self.truth, 0.02 ** 2))
        n = self.truth.size
        self.assertLess(abs(a["relmse_per_run"] - own), 5 * own * math.sqrt(2.0 / n) + 0.1 * self.noise)
        # Without the correction the floor would be the reference's noise (0.25 of per-run relMSE here).
        self.assertLess(abs(a["relmse_floor"]), 0.1 * self.noise)

    def test_a_biased_renderer_has_its_bias_as_floor(self):
        a = peers.agreement(self.renders(0.05), self.reference, self.noise)
        bias_relmse = self.expected_relmse((0.05 * self.truth) ** 2)
        self.assertLess(abs(a["relmse_floor"] - bias_relmse), 0.1 * bias_relmse)
        self.assertGreater(a["mean_difference_z"][0], 5)


if __name__ == "__main__":
    unittest.main()
