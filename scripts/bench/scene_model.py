"""A pathcl scene as the peer exporters see it: camera, materials, and world-space shapes.

The geometry comes from `pathcl info SCENE --dump-obj FILE` (the triangles after pathcl's CGAL clean-up
and transforms, one OBJ object per shape, spheres as comment lines), so every peer gets exactly the
triangles pathcl renders. Materials, emission and the camera come from the scene JSON. Standard library
only: the exporters and their tests run without numpy and without the peers.
"""
import json
import math
import os
import struct
import subprocess
from dataclasses import dataclass, field


@dataclass
class Camera:
    position: tuple
    look_at: tuple
    up: tuple
    fov_y_degrees: float
    width: int
    height: int


# The material types the exporters read (docs/scene-format.md); each exporter maps those its peer renders
# with the same BSDF model and refuses the others (refuse below).
MATERIAL_TYPES = ("diffuse", "oren_nayar", "phong", "mirror", "dielectric", "thin_dielectric", "rough_conductor",
                  "plastic")


@dataclass
class Material:
    """A pathcl material. The fields its type uses are set (pathcl's defaults filled in), the others are None;
    oren_nayar, phong and plastic keep only their type (no peer renders them exactly)."""
    name: str
    type: str = "diffuse"
    place: str = ""             # "scene.json: materials.NAME", for error messages
    reflectance: tuple = None   # diffuse, mirror
    ior: float = None           # dielectric: the inside's index; the front side faces index 1; thin_dielectric
    transmittance: tuple = None  # dielectric: tints each refraction, not reflection; thin_dielectric
    roughness: float = None     # rough_conductor: GGX alpha = roughness^2
    eta: tuple = None           # rough_conductor, and a mirror with a metal's Fresnel term (else None):
                                # complex index eta + i k per channel
    k: tuple = None

    @property
    def alpha(self):
        return self.roughness ** 2


class UnsupportedMaterial(ValueError):
    """A peer has no BSDF that is the same model as this pathcl material."""


def refuse(material, peer, why):
    raise UnsupportedMaterial("%s: %s cannot render pathcl's %s material exactly: %s"
                              % (material.place, peer, material.type, why))


@dataclass
class Shape:
    name: str              # "shapes[3]", the JSON place
    material: str
    emission: tuple
    two_sided: bool
    positions: list = field(default_factory=list)   # world space, [(x, y, z)]
    triangles: list = field(default_factory=list)   # [(i, j, k)] into positions, counter-clockwise = front
    sphere: tuple = None   # (cx, cy, cz, radius, flip_normals) for an analytic sphere

    @property
    def is_emitter(self):
        return any(c > 0 for c in self.emission)


@dataclass
class Scene:
    path: str
    camera: Camera
    materials: dict        # name -> Material
    shapes: list           # [Shape] in scene order
    max_depth: int         # pathcl: largest number of scattering events
    spp: int
    seed: int

    def triangle_count(self):
        return sum(len(s.triangles) for s in self.shapes)

    def used_materials(self):
        """The materials some shape uses, in the order of the scene's `materials` (others never render)."""
        used = {s.material for s in self.shapes}
        return [m for name, m in self.materials.items() if name in used]


# --- vectors --------------------------------------------------------------------------------------

def sub(a, b):
    return tuple(x - y for x, y in zip(a, b))


def add(a, b):
    return tuple(x + y for x, y in zip(a, b))


def scale(a, s):
    return tuple(x * s for x in a)


def dot(a, b):
    return sum(x * y for x, y in zip(a, b))


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def normalize(a):
    length = math.sqrt(dot(a, a))
    return tuple(x / length for x in a)


# --- camera ---------------------------------------------------------------------------------------

def camera_frame(cam):
    """pathcl's right-handed camera frame (scene/device_scene_build.cpp): forward, right, exact up."""
    forward = normalize(sub(cam.look_at, cam.position))
    right = normalize(cross(forward, cam.up))
    up = cross(right, forward)
    return forward, right, up


def pathcl_ray_direction(cam, px, py, jx=0.5, jy=0.5):
    """The unit direction pathcl's camera gives pixel (px, py) at jitter (jx, jy) (docs/scene-format.md)."""
    forward, right, up = camera_frame(cam)
    sx = 2 * (px + jx) / cam.width - 1
    sy = 1 - 2 * (py + jy) / cam.height
    t = math.tan(math.radians(cam.fov_y_degrees) / 2)
    aspect = cam.width / cam.height
    return normalize(add(add(forward, scale(right, sx * t * aspect)), scale(up, sy * t)))


def fov_x_degrees(cam):
    t = math.tan(math.radians(cam.fov_y_degrees) / 2) * cam.width / cam.height
    return math.degrees(2 * math.atan(t))


# --- loading --------------------------------------------------------------------------------------

def read_dump(path):
    """Parses `pathcl info --dump-obj` output: {name: (positions, triangles)} and {name: sphere tuple}."""
    meshes, spheres = {}, {}
    name, base, positions, triangles = None, 1, None, None
    with open(path) as f:
        for line in f:
            parts = line.split()
            if not parts:
                continue
            if parts[0] == "o":
                if name is not None:
                    base += len(positions)
                name, positions, triangles = parts[1], [], []
                meshes[name] = (positions, triangles)
            elif parts[0] == "v":
                positions.append(tuple(float(x) for x in parts[1:4]))
            elif parts[0] == "f":
                triangles.append(tuple(int(x) - base for x in parts[1:4]))
            elif parts[:2] == ["#", "sphere"]:
                cx, cy, cz, r = (float(x) for x in parts[3:7])
                spheres[parts[2]] = (cx, cy, cz, r, parts[7] == "1")
    return meshes, spheres


def _colour(m, key, default, place):
    value = m.get(key, default)
    if not isinstance(value, (list, tuple)):
        raise ValueError("%s.%s: the exporters take [r, g, b] colours, not textures" % (place, key))
    return tuple(float(x) for x in value)


def read_material(name, m, place):
    """A Material from its scene JSON object, with pathcl's defaults and conversions (scene/scene_load.cpp)."""
    t = m["type"]
    if t not in MATERIAL_TYPES:
        raise ValueError("%s.type: unknown material type %r" % (place, t))
    mat = Material(name, t, place)
    if t == "diffuse":
        mat.reflectance = _colour(m, "reflectance", (0.5, 0.5, 0.5), place)
    elif t == "mirror":
        mat.reflectance = _colour(m, "reflectance", (1, 1, 1), place)
        if "eta" in m:
            mat.eta, mat.k = _colour(m, "eta", None, place), _colour(m, "k", None, place)
    elif t in ("dielectric", "thin_dielectric"):
        mat.ior = float(m["ior"])
        mat.transmittance = _colour(m, "transmittance", (1, 1, 1), place)
    elif t == "rough_conductor":
        mat.roughness = float(m["roughness"])
        if "specular" in m:
            # eta = 1 and k = 2 sqrt(r / (1 - r)) reflect exactly r at normal incidence (r at most 0.9999).
            r = [min(c, 0.9999) for c in _colour(m, "specular", None, place)]
            mat.eta, mat.k = (1.0, 1.0, 1.0), tuple(2 * math.sqrt(c / (1 - c)) for c in r)
        else:
            mat.eta, mat.k = _colour(m, "eta", None, place), _colour(m, "k", None, place)
    return mat


def conductor_reflectance(cos_i, eta, k):
    """Fresnel reflectance of a conductor of complex index eta + i k from index 1 (kernels/fresnel.cl)."""
    cos2 = cos_i * cos_i
    sin2 = 1 - cos2
    t0 = eta * eta - k * k - sin2
    a2b2 = math.sqrt(max(t0 * t0 + 4 * eta * eta * k * k, 0))
    a = math.sqrt(max(0.5 * (a2b2 + t0), 0))
    t1, t2 = a2b2 + cos2, 2 * cos_i * a
    rs = (t1 - t2) / (t1 + t2)
    t3, t4 = cos2 * a2b2 + sin2 * sin2, t2 * sin2
    rp = rs * (t3 - t4) / (t3 + t4)
    return 0.5 * (rp + rs)


def is_closed(shape):
    """True for a sphere, or a mesh whose every edge borders exactly two triangles that run through it in
    opposite directions (closed and consistently oriented)."""
    if shape.sphere is not None:
        return True
    edges = {}
    for a, b, c in shape.triangles:
        for e in ((a, b), (b, c), (c, a)):
            edges[e] = edges.get(e, 0) + 1
    return bool(edges) and all(n == 1 and edges.get((b, a)) == 1 for (a, b), n in edges.items())


def dump_scene_obj(pathcl, scene_path, out_path):
    """Runs `pathcl info SCENE --dump-obj OUT`."""
    subprocess.run([pathcl, "info", scene_path, "--dump-obj", out_path], check=True, stdout=subprocess.DEVNULL)


def load(scene_path, dump_path):
    """The scene JSON plus its --dump-obj geometry."""
    with open(scene_path) as f:
        j = json.load(f)
    c = j["camera"]
    camera = Camera(tuple(c["position"]), tuple(c["look_at"]), tuple(c.get("up", (0, 1, 0))),
                    float(c.get("fov_y_degrees", 40)), int(c["width"]), int(c["height"]))
    materials = {name: read_material(name, m, "%s: materials.%s" % (scene_path, name))
                 for name, m in j["materials"].items()}
    meshes, spheres = read_dump(dump_path)
    shapes = []
    for i, s in enumerate(j["shapes"]):
        name = "shapes[%d]" % i
        shape = Shape(name, s["material"], tuple(s.get("emission", (0, 0, 0))), bool(s.get("two_sided", False)))
        if s["type"] == "sphere":
            shape.sphere = spheres[name]
        elif name in meshes:
            shape.positions, shape.triangles = meshes[name]
        shapes.append(shape)
    r = j.get("render", {})
    return Scene(os.path.abspath(scene_path), camera, materials, shapes, int(r.get("max_depth", 8)),
                 int(r.get("spp", 16)), int(r.get("seed", 1)))


# --- geometry output shared by the exporters ------------------------------------------------------

def write_ply(path, positions, triangles, flip=False):
    """Binary little-endian PLY with float32 positions and int32 triangle indices."""
    with open(path, "wb") as f:
        f.write(("ply\nformat binary_little_endian 1.0\ncomment written by pathcl scripts/bench\n"
                 "element vertex %d\nproperty float x\nproperty float y\nproperty float z\n"
                 "element face %d\nproperty list uchar int vertex_indices\nend_header\n"
                 % (len(positions), len(triangles))).encode("ascii"))
        f.write(b"".join(struct.pack("<3f", *p) for p in positions))
        f.write(b"".join(struct.pack("<B3i", 3, a, c, b) if flip else struct.pack("<B3i", 3, a, b, c)
                         for a, b, c in triangles))


def read_ply(path):
    """Reads what write_ply writes (for tests)."""
    with open(path, "rb") as f:
        data = f.read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode("ascii").splitlines()
    nv = int(next(l for l in header if l.startswith("element vertex")).split()[2])
    nf = int(next(l for l in header if l.startswith("element face")).split()[2])
    positions = [struct.unpack_from("<3f", data, end + 12 * i) for i in range(nv)]
    off = end + 12 * nv
    triangles = [struct.unpack_from("<B3i", data, off + 13 * i)[1:] for i in range(nf)]
    return positions, triangles


def icosphere(center, radius, level, flip=False):
    """A sphere as triangles (for peers without analytic spheres): positions on the sphere, CCW outward."""
    t = (1 + math.sqrt(5)) / 2
    v = [normalize(p) for p in [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t),
                                (0, -1, -t), (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2), (10, 7, 6),
         (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10),
         (8, 6, 7), (9, 8, 1)]
    for _ in range(level):
        mid, nf = {}, []

        def midpoint(a, b):
            key = (min(a, b), max(a, b))
            if key not in mid:
                v.append(normalize(scale(add(v[a], v[b]), 0.5)))
                mid[key] = len(v) - 1
            return mid[key]

        for a, b, c in f:
            ab, bc, ca = midpoint(a, b), midpoint(b, c), midpoint(c, a)
            nf += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        f = nf
    positions = [add(center, scale(p, radius)) for p in v]
    return positions, [(a, c, b) for a, b, c in f] if flip else f


def shape_triangles(shape, sphere_level=5):
    """Positions and triangles of a shape, tessellating an analytic sphere."""
    if shape.sphere is None:
        return shape.positions, shape.triangles
    cx, cy, cz, r, flip = shape.sphere
    return icosphere((cx, cy, cz), r, sphere_level, flip)


ICOSPHERE_MESH = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scenes", "meshes",
                                               "icosphere-4.obj"))


def write_icosphere_obj(path=ICOSPHERE_MESH, level=4):
    """Writes the unit icosphere mesh of scenes/glass-metal.json (generated, not committed); the same
    level always gives the same file."""
    positions, triangles = icosphere((0, 0, 0), 1, level)
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    with open(path + ".partial", "w") as f:
        f.write("# Unit sphere as triangles: the icosahedron subdivided %d times, vertices on the unit sphere,\n"
                "# faces counter-clockwise seen from outside. Written by scripts/bench/scene_model.py.\n" % level)
        for p in positions:
            f.write("v %.9g %.9g %.9g\n" % p)
        for a, b, c in triangles:
            f.write("f %d %d %d\n" % (a + 1, b + 1, c + 1))
    os.replace(path + ".partial", path)
    return path


if __name__ == "__main__":
    # python3 scripts/bench/scene_model.py [OUT.obj]: writes the icosphere mesh of scenes/glass-metal.json.
    import sys
    print(write_icosphere_obj(*sys.argv[1:2]))
