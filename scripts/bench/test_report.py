"""report.py's choice of runs: each scene from the newest results file that has it (standard library only)."""
import json
import os
import tempfile
import unittest

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


if __name__ == "__main__":
    unittest.main()
