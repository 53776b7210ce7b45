"""report.py's choice of runs: each scene from the newest results file that has it (standard library only)."""
import json
import os
import tempfile
import unittest

import report


class LatestPerSceneTest(unittest.TestCase):
    def test_each_scene_comes_from_the_newest_run_that_has_it(self):
        runs = {"old.json": {"date": "2026-11-23T14:34:15", "scenes": {"cornell": {"v": 1}, "terrain": {"v": 2}}},
                "new.json": {"date": "2026-11-23T18:40:00", "scenes": {"glass-metal": {"v": 3}, "cornell": {"v": 4}}},
                "mid.json": {"date": "2026-11-23T16:00:00", "scenes": {"cornell": {"v": 5}}}}
        with tempfile.TemporaryDirectory() as tmp:
            paths = []
            for name, run in runs.items():
                paths.append(os.path.join(tmp, name))
                with open(paths[-1], "w") as f:
                    json.dump(run, f)
            scenes = report.latest_per_scene(paths)
        self.assertEqual({k: (e["v"], os.path.basename(p)) for k, (_, e, p) in scenes.items()},
                         {"cornell": (4, "new.json"), "terrain": (2, "old.json"), "glass-metal": (3, "new.json")})


if __name__ == "__main__":
    unittest.main()
