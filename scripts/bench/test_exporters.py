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


# Materials beyond diffuse: a mirror floor, a closed glass tetrahedron, a tinted glass sphere and a light;
# "gold" is unused (never exported, so never refused).
MATERIALS_DUMP = """o shapes[0]
v -1 0 -1
v 1 0 -1
v 1 0 1
v -1 0 1
f 4 3 2
f 4 2 1
o shapes[1]
v 0 0.1 0
v 0.3 0.1 0
v 0 0.1 0.3
v 0 0.4 0
f 5 7 6
f 5 6 8
f 6 7 8
f 7 5 8
# sphere shapes[2] 0.5 0.3 0 0.2 0
o shapes[3]
v -0.2 1.9 -0.2
v 0.2 1.9 -0.2
v 0.2 1.9 0.2
f 9 10 11
"""
MATERIALS_SCENE = {
    "camera": SCENE["camera"],
    "materials": {"metal": {"type": "mirror", "reflectance": [0.9, 0.8, 0.7]},
                  "glass": {"type": "dielectric", "ior": 1.5},
                  "tinted": {"type": "dielectric", "ior": 1.33, "transmittance": [0.9, 0.95, 0.5]},
                  "gold": {"type": "rough_conductor", "roughness": 0.3, "eta": [0.143, 0.374, 1.442],
                           "k": [3.983, 2.385, 1.603]},
                  "lamp": {"type": "diffuse", "reflectance": [0, 0, 0]}},
    "shapes": [{"type": "mesh", "file": "floor.obj", "material": "metal"},
               {"type": "mesh", "file": "tetra.obj", "material": "glass"},
               {"type": "sphere", "radius": 0.2, "center": [0.5, 0.3, 0], "material": "tinted"},
               {"type": "triangles", "positions": [], "indices": [], "material": "lamp", "emission": [17, 12, 4]}],
    "render": {"spp": 8, "max_depth": 6, "seed": 3},
}
# Materials no peer renders exactly (mirrors the exporters' refusals).
INEXPRESSIBLE = {
    "gold": {"type": "rough_conductor", "roughness": 0.3, "eta": [0.143, 0.374, 1.442], "k": [3.983, 2.385, 1.603]},
    "copper": {"type": "rough_conductor", "roughness": 0.15, "specular": [0.95, 0.64, 0.54]},
    "plastic": {"type": "plastic", "diffuse": [0.1, 0.2, 0.6], "ior": 1.5, "roughness": 0.2},
    "phong": {"type": "phong", "diffuse": [0.3, 0.3, 0.3], "specular": [0.5, 0.5, 0.5], "exponent": 40},
}
# The importers' materials: a metal mirror (eta, k) and a thin dielectric; Mitsuba renders both as they are.
IMPORTED = {
    "polished": {"type": "mirror", "reflectance": [0.9, 1, 1], "eta": [0.2, 0.92, 1.1], "k": [3.9, 2.45, 2.14]},
    "pane": {"type": "thin_dielectric", "ior": 1.52, "transmittance": [0.9, 0.95, 1]},
}
REFUSED_BY = {  # peer -> material types it refuses
    "Mitsuba": ("rough_conductor", "oren_nayar", "phong", "plastic"),
    "Cycles": ("rough_conductor", "oren_nayar", "phong", "plastic"),
    "LuxCore": ("rough_conductor", "oren_nayar", "phong", "plastic"),
}


def export_all(scene, out_dir):
    """Runs the three exporters (what peers.py does) into OUT_DIR/{mi,cy,lux}."""
    export_mitsuba.export(scene, os.path.join(out_dir, "mi"))
    export_cycles.export(scene, os.path.join(out_dir, "cy"))
    export_luxcore.export(scene, os.path.join(out_dir, "lux"))


def floats(text, sep=","):
    return [float(x) for x in text.split(sep)]


class MaterialsFixture(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.dir = self.tmp.name
        self.scene = self.load(MATERIALS_SCENE)

    def tearDown(self):
        self.tmp.cleanup()

    def load(self, scene_json, name="materials"):
        path = os.path.join(self.dir, name + ".json")
        with open(path, "w") as f:
            json.dump(scene_json, f)
        with open(os.path.join(self.dir, name + ".obj"), "w") as f:
            f.write(MATERIALS_DUMP)
        return sm.load(path, os.path.join(self.dir, name + ".obj"))

    def with_material(self, shape_index, name, material):
        """MATERIALS_SCENE with shapes[SHAPE_INDEX] made of MATERIAL (named NAME)."""
        j = json.loads(json.dumps(MATERIALS_SCENE))
        j["materials"][name] = material
        j["shapes"][shape_index]["material"] = name
        return self.load(j, "variant")



class ImportedMaterials(MaterialsFixture):
    def test_mitsuba_takes_metal_mirrors_and_thin_glass_and_the_others_refuse_them(self):
        for name, m in IMPORTED.items():
            scene_json = json.loads(json.dumps(MATERIALS_SCENE))
            scene_json["materials"]["metal"] = m
            scene = self.load(scene_json, "imported-" + name)
            xml = open(export_mitsuba.export(scene, os.path.join(self.dir, "mi-" + name))).read()
            if m["type"] == "mirror":
                self.assertIn('<rgb name="eta" value="0.2, 0.92, 1.1"/>', xml)
                self.assertIn('<rgb name="k" value="3.9, 2.45, 2.14"/>', xml)
                self.assertNotIn('value="none"', xml)
            else:
                self.assertIn('<bsdf type="thindielectric">', xml)
                self.assertIn('<float name="int_ior" value="1.52"/>', xml)
                self.assertIn('<rgb name="specular_transmittance" value="0.9, 0.95, 1"/>', xml)
            for peer, export in (("Cycles", export_cycles.export), ("LuxCore", export_luxcore.export)):
                with self.assertRaises(sm.UnsupportedMaterial, msg=peer + " " + name) as caught:
                    export(scene, os.path.join(self.dir, peer + name))
                self.assertIn("materials.metal", str(caught.exception))

class MaterialModelTest(MaterialsFixture):
    def test_materials_with_pathcl_defaults(self):
        m = self.scene.materials
        self.assertEqual((m["metal"].type, m["metal"].reflectance), ("mirror", (0.9, 0.8, 0.7)))
        self.assertEqual((m["glass"].type, m["glass"].ior, m["glass"].transmittance), ("dielectric", 1.5, (1, 1, 1)))
        self.assertEqual(m["tinted"].transmittance, (0.9, 0.95, 0.5))
        self.assertEqual((m["gold"].roughness, m["gold"].eta, m["gold"].k), (0.3, (0.143, 0.374, 1.442),
                                                                             (3.983, 2.385, 1.603)))
        self.assertAlmostEqual(m["gold"].alpha, 0.09)
        self.assertEqual(sm.read_material("m", {"type": "mirror"}, "x").reflectance, (1, 1, 1))
        self.assertEqual([x.name for x in self.scene.used_materials()], ["metal", "glass", "tinted", "lamp"])

    def test_specular_becomes_the_conductor_that_reflects_it_at_normal_incidence(self):
        m = sm.read_material("copper", INEXPRESSIBLE["copper"], "x")
        self.assertEqual(m.eta, (1, 1, 1))
        close(self, m.k, [2 * math.sqrt(r / (1 - r)) for r in (0.95, 0.64, 0.54)])
        for r, eta, k in zip((0.95, 0.64, 0.54), m.eta, m.k):
            self.assertAlmostEqual(sm.conductor_reflectance(1.0, eta, k), r, places=12)
        # A specular of 1 is clamped to 0.9999, as scene/scene_load.cpp does.
        m = sm.read_material("white", {"type": "rough_conductor", "roughness": 0.5, "specular": [1, 1, 1]}, "x")
        self.assertAlmostEqual(m.k[0], 2 * math.sqrt(0.9999 / 0.0001))

    def test_textures_and_unknown_types_are_refused_by_name(self):
        with self.assertRaisesRegex(ValueError, r"s.json: materials.wood.reflectance: .*not textures"):
            sm.read_material("wood", {"type": "diffuse", "reflectance": {"texture": "w.png"}}, "s.json: materials.wood")
        with self.assertRaisesRegex(ValueError, r"materials.x.type: unknown material type 'glas'"):
            sm.read_material("x", {"type": "glas"}, "s.json: materials.x")

    def test_closed_meshes(self):
        s = self.scene.shapes
        self.assertFalse(sm.is_closed(s[0]))  # the floor quad
        self.assertTrue(sm.is_closed(s[1]))   # the tetrahedron
        self.assertTrue(sm.is_closed(s[2]))   # a sphere
        pos, tri = sm.icosphere((0, 0, 0), 1, 2)
        shape = sm.Shape("s", "glass", (0, 0, 0), False, pos, tri)
        self.assertTrue(sm.is_closed(shape))
        shape.triangles = tri[:-1]  # a hole
        self.assertFalse(sm.is_closed(shape))
        shape.triangles = tri[:-1] + [(tri[-1][0], tri[-1][2], tri[-1][1])]  # one face turned over
        self.assertFalse(sm.is_closed(shape))

    def test_every_exporter_refuses_what_its_peer_cannot_render_exactly(self):
        cases = dict(INEXPRESSIBLE, rough={"type": "oren_nayar", "reflectance": [0.5, 0.5, 0.5], "sigma_degrees": 20})
        exporters = {"Mitsuba": lambda sc, d: export_mitsuba.export(sc, d),
                     "Cycles": lambda sc, d: export_cycles.export(sc, d),
                     "LuxCore": lambda sc, d: export_luxcore.export(sc, d)}
        for name, material in cases.items():
            scene = self.with_material(2, name, material)
            for peer, export in exporters.items():
                self.assertIn(material["type"], REFUSED_BY[peer])
                with self.subTest(material=name, peer=peer):
                    with self.assertRaises(sm.UnsupportedMaterial) as cm:
                        export(scene, os.path.join(self.dir, peer))
                    msg = str(cm.exception)
                    self.assertIn("variant.json: materials.%s: %s cannot render pathcl's %s material exactly"
                                  % (name, peer, material["type"]), msg)

    def test_the_refusals_name_the_difference(self):
        scene = self.with_material(2, "gold", INEXPRESSIBLE["gold"])
        for export, words in ((export_mitsuba.export, ("separable", "G1(wi) G1(wo)", "height-correlated")),
                              (export_cycles.export, ("no conductor Fresnel", "G1(wi) G1(wo)", "mirror")),
                              (export_luxcore.export, ("metal2", "Schlick", "uroughness"))):
            with self.assertRaises(sm.UnsupportedMaterial) as cm:
                export(scene, os.path.join(self.dir, "x"))
            for w in words:
                self.assertIn(w, str(cm.exception))

    def test_all_exporters_take_mirror_and_dielectric(self):
        export_all(self.scene, self.dir)  # no refusal: "gold" is not used


class MitsubaMaterialsTest(MaterialsFixture):
    def setUp(self):
        super().setUp()
        root = ET.parse(export_mitsuba.export(self.scene, os.path.join(self.dir, "mi"))).getroot()
        self.bsdfs = {b.get("id"): b for b in root.findall("bsdf")}
        self.shapes = root.findall("shape")

    def test_mirror_is_a_two_sided_conductor_of_no_material(self):
        metal = self.bsdfs["mat-metal"]
        self.assertEqual(metal.get("type"), "twosided")
        inner = metal.find("bsdf")
        self.assertEqual(inner.get("type"), "conductor")
        self.assertEqual(inner.find("string[@name='material']").get("value"), "none")
        close(self, floats(inner.find("rgb[@name='specular_reflectance']").get("value")), (0.9, 0.8, 0.7))
        # Mitsuba's "none" is the complex index 0 + 1i, whose Fresnel reflectance is 1 at every angle.
        for cos in (1.0, 0.7, 0.3, 0.05):
            self.assertAlmostEqual(sm.conductor_reflectance(cos, 0.0, 1.0), 1.0, places=12)
        self.assertEqual(self.shapes[0].find("ref").get("id"), "mat-metal")

    def test_dielectric_is_one_sided_with_air_of_index_1(self):
        for name, ior, transmittance in (("glass", 1.5, (1, 1, 1)), ("tinted", 1.33, (0.9, 0.95, 0.5))):
            b = self.bsdfs["mat-" + name]
            self.assertEqual(b.get("type"), "dielectric")  # not wrapped in twosided: the sides differ
            values = {e.get("name"): e.get("value") for e in b}
            self.assertEqual(float(values["int_ior"]), ior)
            self.assertEqual(float(values["ext_ior"]), 1.0)  # Mitsuba's default is air, 1.000277
            close(self, floats(values["specular_transmittance"]), transmittance)
            self.assertNotIn("specular_reflectance", values)  # reflection untinted (default 1)
        self.assertEqual(self.shapes[1].find("ref").get("id"), "mat-glass")
        self.assertEqual(self.shapes[2].get("type"), "sphere")
        self.assertEqual(self.shapes[2].find("ref").get("id"), "mat-tinted")

    def test_unused_materials_are_not_written(self):
        self.assertNotIn("mat-gold", self.bsdfs)


class FakeNode:
    """Just enough of a bpy shader node for the generated Cycles script."""

    class Socket:
        def __init__(self, node, name):
            self.node, self.name, self.default_value = node, name, None

    class Sockets(dict):
        def __init__(self, node):
            super().__init__()
            self.node = node

        def __getitem__(self, key):
            if key not in self:
                self[key] = FakeNode.Socket(self.node, key)
            return dict.__getitem__(self, key)

    def __init__(self, kind):
        self.kind, self.distribution = kind, None
        self.inputs, self.outputs = FakeNode.Sockets(self), FakeNode.Sockets(self)


class FakeTree:
    def __init__(self):
        self.nodes_made, self.links_made = [], []
        tree = self

        class Nodes:
            def new(self, kind):
                tree.nodes_made.append(FakeNode(kind))
                return tree.nodes_made[-1]

            def clear(self):
                tree.nodes_made.clear()

        class Links:
            def new(self, a, b):
                tree.links_made.append((a, b))

        self.nodes, self.links = Nodes(), Links()

    def source(self, socket):
        """The output socket linked into input SOCKET."""
        return next(a for a, b in self.links_made if b is socket)


def cycles_script_functions():
    """The generated Blender script's functions, defined with stand-ins for bpy and mathutils (not run)."""
    import types
    fake = {"bpy": types.ModuleType("bpy"), "mathutils": types.ModuleType("mathutils")}
    fake["mathutils"].Matrix = None
    saved = {k: sys.modules.get(k) for k in fake}
    sys.modules.update(fake)
    try:
        namespace = {"__file__": os.path.join(HERE, "cycles_scene.py"), "__name__": "cycles_scene"}
        exec(compile(export_cycles.BLENDER_SCRIPT.rsplit("\nmain()", 1)[0], "cycles_scene.py", "exec"), namespace)
    finally:
        for k, v in saved.items():
            if v is None:
                del sys.modules[k]
            else:
                sys.modules[k] = v
    return namespace


class CyclesMaterialsTest(MaterialsFixture):
    def setUp(self):
        super().setUp()
        self.script = export_cycles.export(self.scene, os.path.join(self.dir, "cy"))
        with open(os.path.join(self.dir, "cy", "cycles.json")) as f:
            self.data = json.load(f)
        self.surface = cycles_script_functions()["surface"]

    def test_material_data(self):
        m = self.data["materials"]
        self.assertEqual(m["metal"], {"type": "mirror", "reflectance": [0.9, 0.8, 0.7]})
        self.assertEqual(m["glass"], {"type": "dielectric", "ior": 1.5, "transmittance": [1, 1, 1]})
        self.assertEqual(m["tinted"], {"type": "dielectric", "ior": 1.33, "transmittance": [0.9, 0.95, 0.5]})
        self.assertNotIn("gold", m)

    def test_mirror_is_a_sharp_glossy_bsdf(self):
        tree = FakeTree()
        out = self.surface(tree, self.data["materials"]["metal"])
        node = out.node
        self.assertEqual((node.kind, node.distribution, out.name), ("ShaderNodeBsdfGlossy", "SHARP", "BSDF"))
        self.assertEqual(node.inputs["Color"].default_value, (0.9, 0.8, 0.7, 1.0))

    def test_dielectric_is_fresnel_mix_of_sharp_refraction_and_reflection(self):
        tree = FakeTree()
        out = self.surface(tree, self.data["materials"]["tinted"])
        mix = out.node
        self.assertEqual(mix.kind, "ShaderNodeMixShader")
        fresnel = tree.source(mix.inputs["Fac"]).node  # factor 1 takes input 2: reflection with weight F
        refraction = tree.source(mix.inputs[1]).node
        reflection = tree.source(mix.inputs[2]).node
        self.assertEqual(fresnel.kind, "ShaderNodeFresnel")
        self.assertEqual(fresnel.inputs["IOR"].default_value, 1.33)
        self.assertEqual((refraction.kind, refraction.distribution), ("ShaderNodeBsdfRefraction", "SHARP"))
        self.assertEqual(refraction.inputs["IOR"].default_value, 1.33)
        self.assertEqual(refraction.inputs["Color"].default_value, (0.9, 0.95, 0.5, 1.0))
        self.assertEqual((reflection.kind, reflection.distribution), ("ShaderNodeBsdfGlossy", "SHARP"))
        self.assertEqual(reflection.inputs["Color"].default_value, (1.0, 1.0, 1.0, 1.0))

    def test_caustics_on(self):
        with open(self.script) as f:
            text = f.read()
        for setting in ("caustics_reflective = True", "caustics_refractive = True", "blur_glossy = 0.0"):
            self.assertIn(setting, text)

    def test_dielectric_on_an_open_mesh_is_refused(self):
        scene = self.with_material(0, "glass", MATERIALS_SCENE["materials"]["glass"])
        with self.assertRaisesRegex(sm.UnsupportedMaterial, r"variant.json: shapes\[0\] \(material glass\): Cycles "
                                    r"cannot render pathcl's dielectric exactly on an open .*\(n_i / n_t\)\^2"):
            export_cycles.export(scene, os.path.join(self.dir, "cy2"))
        # Mitsuba and LuxCore scale radiance as pathcl does: open glass is fine there.
        export_mitsuba.export(scene, os.path.join(self.dir, "mi2"))
        export_luxcore.export(scene, os.path.join(self.dir, "lux2"))


class LuxCoreMaterialsTest(MaterialsFixture):
    def setUp(self):
        super().setUp()
        export_luxcore.export(self.scene, os.path.join(self.dir, "lux"))
        with open(os.path.join(self.dir, "lux", "scene.scn")) as f:
            self.scn = export_luxcore.parse_properties(f.read())

    def test_mirror(self):
        self.assertEqual(self.scn["scene.materials.metal.type"], ["mirror"])
        close(self, [float(x) for x in self.scn["scene.materials.metal.kr"]], (0.9, 0.8, 0.7))
        self.assertEqual(self.scn["scene.objects.shape0.material"], ["metal"])

    def test_glass(self):
        for name, ior, kt in (("glass", 1.5, (1, 1, 1)), ("tinted", 1.33, (0.9, 0.95, 0.5))):
            p = "scene.materials.%s." % name
            self.assertEqual(self.scn[p + "type"], ["glass"])
            self.assertEqual(float(self.scn[p + "interiorior"][0]), ior)
            self.assertEqual(float(self.scn[p + "exteriorior"][0]), 1.0)
            close(self, [float(x) for x in self.scn[p + "kr"]], (1, 1, 1))  # reflection untinted
            close(self, [float(x) for x in self.scn[p + "kt"]], kt)
        self.assertEqual(self.scn["scene.objects.shape1.material"], ["glass"])
        self.assertEqual(self.scn["scene.objects.shape2.material"], ["tinted"])
        self.assertNotIn("scene.materials.gold.type", self.scn)

    def test_an_emitter_copies_its_material(self):
        scene = self.with_material(3, "lampglass", {"type": "mirror", "reflectance": [0.5, 0.5, 0.5]})
        lines, _ = export_luxcore.scene_properties(scene)
        scn = export_luxcore.parse_properties("\n".join(lines))
        self.assertEqual(scn["scene.materials.lampglass_emit3.type"], ["mirror"])
        close(self, [float(x) for x in scn["scene.materials.lampglass_emit3.kr"]], (0.5, 0.5, 0.5))
        close(self, [float(x) for x in scn["scene.materials.lampglass_emit3.emission"]], (17, 12, 4))


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

    def test_glass_metal_scene_is_the_cornell_box_with_a_glass_and_a_mirror_sphere(self):
        sm.write_icosphere_obj()  # generated, not committed
        with tempfile.TemporaryDirectory() as tmp:
            scenes = {}
            for name in ("cornell-official", "glass-metal"):
                path = os.path.join(ROOT, "scenes", name + ".json")
                dump = os.path.join(tmp, name + ".obj")
                sm.dump_scene_obj(os.environ["PATHCL"], path, dump)
                scenes[name] = sm.load(path, dump)
            cornell, scene = scenes["cornell-official"], scenes["glass-metal"]
            self.assertEqual(scene.camera, cornell.camera)
            self.assertEqual((scene.max_depth, scene.spp), (cornell.max_depth, cornell.spp))
            for i in (0, 1, 2, 3, 4):  # the walls
                self.assertEqual(scene.shapes[i].positions, cornell.shapes[i].positions)
                a, b = scene.materials[scene.shapes[i].material], cornell.materials[cornell.shapes[i].material]
                self.assertEqual((a.type, a.reflectance), (b.type, b.reflectance))
            self.assertEqual(scene.shapes[7].positions, cornell.shapes[7].positions)  # the light
            self.assertEqual(scene.shapes[7].emission, cornell.shapes[7].emission)
            glass, metal = (scene.materials[scene.shapes[i].material] for i in (5, 6))
            self.assertEqual((glass.type, glass.ior, glass.transmittance), ("dielectric", 1.5, (1, 1, 1)))
            self.assertEqual(metal.type, "mirror")
            # Both spheres are the same closed triangle mesh in every renderer (Cycles and LuxCore have no
            # analytic spheres), the glass one where the short block stood, the mirror one at the tall block.
            for shape, centre in ((scene.shapes[5], (186, 90, 168.5)), (scene.shapes[6], (368.5, 90, 351.5))):
                self.assertEqual(len(shape.triangles), 5120)
                self.assertTrue(sm.is_closed(shape))
                for p in shape.positions:
                    self.assertAlmostEqual(math.dist(p, centre), 90, delta=1e-3)
            export_all(scene, tmp)  # every peer takes it


if __name__ == "__main__":
    unittest.main()
