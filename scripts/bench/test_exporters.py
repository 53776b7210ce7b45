"""Unit tests of the peer exporters (standard library only: no peers, no numpy, no network).

Run: python3 -m unittest discover -s scripts/bench -p 'test_*.py'   (CTest: bench_exporters_test)
With $PATHCL naming a pathcl binary, the Cornell benchmark scene is also dumped with `pathcl info
--dump-obj` and checked against its OBJ files.
"""
import json
import math
import os
import subprocess
import sys
import tempfile
import unittest
import xml.etree.ElementTree as ET

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, HERE)

import export_cycles  # noqa: E402
import export_luxcore  # noqa: E402
import export_mitsuba  # noqa: E402
import scene_model as sm  # noqa: E402

# A dump as `pathcl info --dump-obj` writes it: a quad floor, a sphere, a one-sided and a two-sided light.
DUMP = """# pathcl info --dump-obj: cleaned world-space triangles of test.json
o shapes[0]
v -1 0 -1
v 1 0 -1
v 1 0 1
v -1 0 1
f 4 3 2
f 4 2 1
# sphere shapes[1] 0 0.5 0 0.25 0
o shapes[2]
v -0.2 1.9 -0.2
v 0.2 1.9 -0.2
v 0.2 1.9 0.2
f 5 6 7
o shapes[3]
v 0.5 1 0
v 0.6 1 0
v 0.5 1.1 0
f 8 9 10
"""
SCENE = {
    "camera": {"position": [0.3, 1.2, 3.5], "look_at": [0, 0.8, 0], "up": [0.1, 1, 0], "fov_y_degrees": 35,
               "width": 48, "height": 32},
    "materials": {"white": {"type": "diffuse", "reflectance": [0.725, 0.71, 0.68]},
                  "lamp": {"type": "diffuse", "reflectance": [0, 0, 0]}},
    "shapes": [{"type": "mesh", "file": "floor.obj", "material": "white"},
               {"type": "sphere", "radius": 0.25, "center": [0, 0.5, 0], "material": "white"},
               {"type": "triangles", "positions": [], "indices": [], "material": "lamp", "emission": [17, 12, 4]},
               {"type": "triangles", "positions": [], "indices": [], "material": "lamp", "emission": [1, 2, 3],
                "two_sided": True}],
    "render": {"spp": 8, "max_depth": 6, "seed": 3},
}
PIXELS = [(0, 0), (47, 0), (0, 31), (47, 31), (20, 11), (33, 25)]


def close(test, a, b, tol=1e-6):
    test.assertEqual(len(a), len(b))
    for x, y in zip(a, b):
        test.assertAlmostEqual(x, y, delta=tol)


class Fixture(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.dir = self.tmp.name
        with open(os.path.join(self.dir, "test.json"), "w") as f:
            json.dump(SCENE, f)
        with open(os.path.join(self.dir, "test.obj"), "w") as f:
            f.write(DUMP)
        self.scene = sm.load(os.path.join(self.dir, "test.json"), os.path.join(self.dir, "test.obj"))

    def tearDown(self):
        self.tmp.cleanup()

    def pixel_directions(self):
        return [sm.pathcl_ray_direction(self.scene.camera, px, py, 0.5, 0.5) for px, py in PIXELS]


class SceneModelTest(Fixture):
    def test_dump_gives_per_shape_world_triangles_and_spheres(self):
        s = self.scene.shapes
        self.assertEqual([x.name for x in s], ["shapes[0]", "shapes[1]", "shapes[2]", "shapes[3]"])
        self.assertEqual(s[0].positions, [(-1, 0, -1), (1, 0, -1), (1, 0, 1), (-1, 0, 1)])
        self.assertEqual(s[0].triangles, [(3, 2, 1), (3, 1, 0)])  # 0-based within the shape
        self.assertEqual(s[2].triangles, [(0, 1, 2)])
        self.assertEqual(s[1].sphere, (0, 0.5, 0, 0.25, False))
        self.assertEqual(self.scene.triangle_count(), 4)
        self.assertEqual(s[2].emission, (17, 12, 4))
        self.assertTrue(s[2].is_emitter and not s[2].two_sided and s[3].two_sided and not s[0].is_emitter)
        self.assertEqual(self.scene.materials["white"].reflectance, (0.725, 0.71, 0.68))
        self.assertEqual((self.scene.max_depth, self.scene.spp, self.scene.seed), (6, 8, 3))

    def test_camera_directions_follow_the_documented_formula(self):
        cam = self.scene.camera
        d = sm.pathcl_ray_direction(cam, cam.width / 2 - 0.5, cam.height / 2 - 0.5)
        close(self, d, sm.normalize(sm.sub(cam.look_at, cam.position)))
        # The top-left pixel looks up and to the left: positive up', negative right components.
        forward, right, up = sm.camera_frame(cam)
        d = sm.pathcl_ray_direction(cam, 0, 0)
        self.assertGreater(sm.dot(d, up), 0)
        self.assertLess(sm.dot(d, right), 0)

    def test_ply_round_trip_and_flip(self):
        path = os.path.join(self.dir, "t.ply")
        sm.write_ply(path, self.scene.shapes[0].positions, self.scene.shapes[0].triangles, flip=True)
        pos, tri = sm.read_ply(path)
        close(self, [c for p in pos for c in p], [c for p in self.scene.shapes[0].positions for c in p])
        self.assertEqual(tri, [(3, 1, 2), (3, 0, 1)])

    def test_icosphere_is_on_the_sphere_and_outward(self):
        pos, tri = sm.icosphere((1, 2, 3), 0.5, 2)
        self.assertEqual(len(tri), 20 * 16)
        for p in pos:
            self.assertAlmostEqual(math.dist(p, (1, 2, 3)), 0.5, places=9)
        a, b, c = (pos[i] for i in tri[0])
        n = sm.cross(sm.sub(b, a), sm.sub(c, a))
        self.assertGreater(sm.dot(n, sm.sub(a, (1, 2, 3))), 0)


class MitsubaTest(Fixture):
    def setUp(self):
        super().setUp()
        self.xml = export_mitsuba.export(self.scene, os.path.join(self.dir, "mi"))
        self.root = ET.parse(self.xml).getroot()

    def defaults(self):
        return {d.get("name"): d.get("value") for d in self.root.findall("default")}

    def test_depth_and_roulette_mapping(self):
        self.assertEqual(export_mitsuba.max_depth(0), 1)  # emitters seen directly
        self.assertEqual(export_mitsuba.max_depth(1), 2)  # direct light
        self.assertEqual(self.defaults()["max_depth"], "7")
        integ = self.root.find("integrator")
        self.assertEqual(integ.get("type"), "path")
        values = {e.get("name"): e.get("value") for e in integ}
        self.assertEqual(values["max_depth"], "$max_depth")
        self.assertEqual(values["rr_depth"], "4")
        self.assertEqual(self.defaults()["spp"], "8")

    def test_camera_gives_the_same_ray_directions(self):
        sensor = self.root.find("sensor")
        floats = {e.get("name"): float(e.get("value")) for e in sensor.findall("float")}
        self.assertEqual(sensor.find("string[@name='fov_axis']").get("value"), "y")
        la = sensor.find("transform/lookat")
        origin, target, up = (tuple(float(x) for x in la.get(k).split(",")) for k in ("origin", "target", "up"))
        close(self, origin, self.scene.camera.position)
        film = sensor.find("film")
        w = int(film.find("integer[@name='width']").get("value"))
        h = int(film.find("integer[@name='height']").get("value"))
        self.assertEqual(film.find("rfilter").get("type"), "box")  # radius 0.5: one pixel wide
        # Mitsuba's look-at frame: dir, left = cross(up, dir), up' = cross(dir, left); its perspective
        # camera maps film x in [0, 1] to -left (the image's right) and film y in [0, 1] downwards.
        d = sm.normalize(sm.sub(target, origin))
        left = sm.normalize(sm.cross(up, d))
        new_up = sm.cross(d, left)
        ty = math.tan(math.radians(floats["fov"]) / 2)
        for (px, py), expected in zip(PIXELS, self.pixel_directions()):
            x, y = (px + 0.5) / w, (py + 0.5) / h
            local = ((2 * x - 1) * ty * w / h, (1 - 2 * y) * ty, 1.0)
            got = sm.normalize(sm.add(sm.add(sm.scale(left, -local[0]), sm.scale(new_up, local[1])), d))
            close(self, got, expected)

    def test_materials_two_sided_and_emitters_one_sided(self):
        bsdfs = {b.get("id"): b for b in self.root.findall("bsdf")}
        white = bsdfs["mat-white"]
        self.assertEqual(white.get("type"), "twosided")
        self.assertEqual(white.find("bsdf").get("type"), "diffuse")
        close(self, [float(x) for x in white.find("bsdf/rgb").get("value").split(",")], (0.725, 0.71, 0.68))
        shapes = self.root.findall("shape")
        self.assertEqual([s.get("type") for s in shapes], ["ply", "sphere", "ply", "ply", "ply"])
        self.assertEqual(shapes[0].find("boolean[@name='face_normals']").get("value"), "true")
        self.assertIsNone(shapes[0].find("emitter"))
        self.assertEqual(shapes[2].find("emitter").get("type"), "area")
        close(self, [float(x) for x in shapes[2].find("emitter/rgb").get("value").split(",")], (17, 12, 4))
        # The two-sided light: the same triangle twice, the second reversed.
        front = sm.read_ply(os.path.join(self.dir, "mi", shapes[3].find("string").get("value")))
        back = sm.read_ply(os.path.join(self.dir, "mi", shapes[4].find("string").get("value")))
        self.assertEqual(front[1], [(0, 1, 2)])
        self.assertEqual(back[1], [(0, 2, 1)])
        self.assertIsNotNone(shapes[4].find("emitter"))

    def test_meshes_carry_the_dumped_vertices(self):
        ply = self.root.findall("shape")[0].find("string").get("value")
        pos, tri = sm.read_ply(os.path.join(self.dir, "mi", ply))
        close(self, [c for p in pos for c in p], [c for p in self.scene.shapes[0].positions for c in p])
        self.assertEqual(tri, self.scene.shapes[0].triangles)
        sphere = self.root.findall("shape")[1]
        self.assertEqual(float(sphere.find("float[@name='radius']").get("value")), 0.25)


class CyclesTest(Fixture):
    def setUp(self):
        super().setUp()
        self.script = export_cycles.export(self.scene, os.path.join(self.dir, "cy"))
        with open(os.path.join(self.dir, "cy", "cycles.json")) as f:
            self.data = json.load(f)

    def test_depth_mapping(self):
        self.assertEqual(export_cycles.max_bounces(1), 0)  # max_bounces 0: one scattering event
        self.assertEqual(export_cycles.max_bounces(8), 7)
        self.assertEqual(self.data["max_bounces"], 5)
        self.assertEqual(self.data["min_light_bounces"], 2)
        with self.assertRaises(ValueError):
            export_cycles.max_bounces(0)

    def test_camera_gives_the_same_ray_directions(self):
        m = self.data["camera"]["matrix"]
        c = self.scene.camera
        ty = math.tan(self.data["camera"]["angle_y"] / 2)
        aspect = self.data["camera"]["width"] / self.data["camera"]["height"]
        close(self, [m[r][3] for r in range(3)], c.position)
        for (px, py), expected in zip(PIXELS, self.pixel_directions()):
            # Blender camera: looks down local -z, +x right and +y up in the image, sensor fit vertical.
            local = ((2 * (px + 0.5) / c.width - 1) * ty * aspect, (1 - 2 * (py + 0.5) / c.height) * ty, -1.0)
            world = tuple(sum(m[r][k] * local[k] for k in range(3)) for r in range(3))
            close(self, sm.normalize(world), expected)

    def test_materials_lights_and_meshes(self):
        self.assertEqual(self.data["materials"]["white"]["reflectance"], [0.725, 0.71, 0.68])
        shapes = {s["name"]: s for s in self.data["shapes"]}
        self.assertEqual(shapes["shapes[2]"]["emission"], [17, 12, 4])
        self.assertFalse(shapes["shapes[2]"]["two_sided"])
        self.assertTrue(shapes["shapes[3]"]["two_sided"])
        pos, tri = sm.read_ply(os.path.join(self.dir, "cy", shapes["shapes[0]"]["ply"]))
        self.assertEqual(tri, self.scene.shapes[0].triangles)
        pos, tri = sm.read_ply(os.path.join(self.dir, "cy", shapes["shapes[1]"]["ply"]))
        self.assertEqual(len(tri), 20 * 4 ** 5)  # the tessellated sphere
        for p in pos:
            self.assertAlmostEqual(math.dist(p, (0, 0.5, 0)), 0.25, places=6)

    def test_generated_script_compiles_and_turns_features_off(self):
        with open(self.script) as f:
            text = f.read()
        compile(text, self.script, "exec")
        for setting in ("use_adaptive_sampling = False", "use_denoising = False", "sample_clamp_direct = 0.0",
                        "sample_clamp_indirect = 0.0", "light_sampling_threshold = 0.0", "use_light_tree = False",
                        'pixel_filter_type = "BOX"', "filter_width = 1.0", '"Backfacing"'):
            self.assertIn(setting, text)


class LuxCoreTest(Fixture):
    def setUp(self):
        super().setUp()
        cfg = export_luxcore.export(self.scene, os.path.join(self.dir, "lux"))
        with open(cfg) as f:
            self.cfg = export_luxcore.parse_properties(f.read())
        with open(os.path.join(self.dir, "lux", "scene.scn")) as f:
            self.scn = export_luxcore.parse_properties(f.read())

    def test_depth_roulette_filter(self):
        self.assertEqual(export_luxcore.path_depth(1), 1)
        self.assertEqual(self.cfg["path.pathdepth.total"], ["6"])
        self.assertEqual(self.cfg["path.pathdepth.diffuse"], ["6"])
        self.assertEqual(self.cfg["path.russianroulette.depth"], ["4"])
        self.assertEqual(self.cfg["path.russianroulette.cap"], ["0"])
        self.assertEqual(self.cfg["film.filter.type"], ["BOX"])
        self.assertEqual(self.cfg["film.filter.width"], ["0.5"])
        self.assertEqual(self.cfg["batch.haltspp"], ["8"])
        self.assertEqual(self.cfg["film.outputs.0.type"], ["RGB"])
        pathocl = export_luxcore.parse_properties("\n".join(export_luxcore.render_properties(self.scene, "PATHOCL")))
        self.assertEqual(pathocl["renderengine.type"], ["PATHOCL"])
        self.assertEqual(pathocl["opencl.cpu.use"], ["1"])

    def test_camera_gives_the_same_ray_directions(self):
        v = lambda key: tuple(float(x) for x in self.scn[key])
        orig, target, up = v("scene.camera.lookat.orig"), v("scene.camera.lookat.target"), v("scene.camera.up")
        fov = float(self.scn["scene.camera.fieldofview"][0])
        x0, x1, y0, y1 = v("scene.camera.screenwindow") + ()
        c = self.scene.camera
        d = sm.normalize(sm.sub(target, orig))
        right = sm.normalize(sm.cross(d, up))
        new_up = sm.cross(right, d)
        t = math.tan(math.radians(fov) / 2)
        for (px, py), expected in zip(PIXELS, self.pixel_directions()):
            # Screen window spans the film: x from x0 (left) to x1, y from y1 (top) to y0, scaled by tan(fov/2).
            sx = x0 + (x1 - x0) * (px + 0.5) / c.width
            # pyluxcore 2.11 shows at row r what the window puts at row r - 1 (export_luxcore.ROW_OFFSET_PIXELS).
            row = py + 0.5 - export_luxcore.ROW_OFFSET_PIXELS
            sy = y1 - (y1 - y0) * row / c.height
            got = sm.normalize(sm.add(sm.add(d, sm.scale(right, sx * t)), sm.scale(new_up, sy * t)))
            close(self, got, expected)

    def test_materials_and_lights(self):
        self.assertEqual(self.scn["scene.materials.white.type"], ["matte"])
        close(self, [float(x) for x in self.scn["scene.materials.white.kd"]], (0.725, 0.71, 0.68))
        self.assertEqual(self.scn["scene.objects.shape2.material"], ["lamp_emit2"])
        close(self, [float(x) for x in self.scn["scene.materials.lamp_emit2.emission"]], (17, 12, 4))
        self.assertNotIn("scene.objects.shape2back.shape", self.scn)  # one-sided
        self.assertIn("scene.objects.shape3back.shape", self.scn)     # two-sided: a reversed copy
        _, tri = sm.read_ply(os.path.join(self.dir, "lux", self.scn["scene.shapes.shape3back.ply"][0]))
        self.assertEqual(tri, [(0, 2, 1)])
        pos, tri = sm.read_ply(os.path.join(self.dir, "lux", self.scn["scene.shapes.shape0.ply"][0]))
        self.assertEqual(tri, self.scene.shapes[0].triangles)


@unittest.skipUnless(os.environ.get("PATHCL"), "set PATHCL to a pathcl binary")
class DumpIntegrationTest(unittest.TestCase):
    def test_cornell_dump_matches_its_obj_files(self):
        scene_path = os.path.join(ROOT, "scenes", "cornell-official.json")
        with tempfile.TemporaryDirectory() as tmp:
            dump = os.path.join(tmp, "cornell.obj")
            sm.dump_scene_obj(os.environ["PATHCL"], scene_path, dump)
            scene = sm.load(scene_path, dump)
        self.assertEqual(scene.triangle_count(), 32)  # 6 quads + 2 blocks of 5 quads, 2 triangles each
        floor = scene.shapes[0]
        close(self, [c for p in floor.positions for c in p],
              [552.8, 0, 0, 0, 0, 0, 0, 0, 559.2, 549.6, 0, 559.2], 1e-4)
        light = scene.shapes[7]
        self.assertEqual(light.emission, (17, 12, 4))
        for a, b, c in light.triangles:  # the light faces down
            n = sm.cross(sm.sub(light.positions[b], light.positions[a]), sm.sub(light.positions[c], light.positions[a]))
            self.assertLess(n[1], 0)
        self.assertTrue(all(p[1] == light.positions[0][1] for p in light.positions))
        self.assertAlmostEqual(light.positions[0][1], 548.7, places=3)


if __name__ == "__main__":
    unittest.main()
