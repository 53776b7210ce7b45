"""Exports a pathcl scene (scene_model.Scene) to a Blender Python script that builds it for Cycles.

`blender -b --factory-startup --python OUT/cycles_scene.py -- --spp N --seed S --out IMAGE.exr` builds the
scene from OUT/cycles.json and OUT/meshes/*.ply and renders it; `--spp-series 1,4,16` renders several
sample counts in one process (the scene is built once) and `--time T` sets Cycles' time limit. The script
prints one line `PATHCL_BENCH {json}` per render with the setup and render seconds.

Mapping:
- Camera: a Blender camera looks down its local -z with +x right and +y up in the image, so its world
  matrix has the columns (right, up', -forward, position) of pathcl's frame; sensor fit vertical with
  `angle_y` = fov_y. Pixel filter: box, width 1 pixel.
- Depth: Cycles' `max_bounces = N` allows N + 1 scattering events, so N = pathcl max_depth - 1 (and the
  same for diffuse bounces). Russian roulette: Cycles starts it once `bounce > min_light_bounces`, where
  bounce counts scattering events before the current one, so min_light_bounces = 3 - 1 = 2 starts it at
  the 4th scattering event as in pathcl; Cycles' survival probability is sqrt(max throughput) (pathcl's:
  max throughput), unbiased either way.
- Off: adaptive sampling, denoising, clamping (direct and indirect), the light threshold, the light tree
  (Blender >= 3.5 only; Blender 3.4 has none).
- Materials (only those with the same BSDF model; the others are refused, naming the material). Cycles
  turns the shading frame towards the viewer, so every BSDF reflects on both sides as in pathcl:
  - `diffuse`: Diffuse BSDF with roughness 0 (Lambertian).
  - `mirror`: Glossy BSDF with the Sharp distribution (a delta reflection of weight Color, no Fresnel).
  - `dielectric`: a Mix shader whose factor is a Fresnel node (IOR = ior) between a Sharp Refraction BSDF
    (Color = transmittance, IOR = ior) and a white Sharp Glossy BSDF. The Fresnel node computes the exact
    dielectric Fresnel term with the index inverted on back faces (Backfacing: inside), as the Glass BSDF
    does, so reflection has weight F and refraction (1 - F) transmittance, as in pathcl; the Glass BSDF
    itself tints reflection too and gives refraction at least the weight 1e-4. Cycles does not scale
    radiance by (n_i / n_t)^2 on refraction as pathcl does; along a path the factors cancel where it leaves
    every object it entered before it reaches a light or a non-delta surface, so dielectrics are accepted
    only on closed, consistently oriented meshes and spheres (with nothing inside them: not checked).
  - `rough_conductor` is refused: the GGX Glossy BSDF of Blender 3.4 (alpha = Roughness^2, as pathcl) has
    no conductor Fresnel term and the separable masking-shadowing G1(wi) G1(wo), pathcl's the
    height-correlated 1 / (1 + Lambda(wi) + Lambda(wo)). oren_nayar, phong and plastic are refused too.
  Caustics are on (reflective and refractive) and Filter Glossy is 0, so no specular path is cut or blurred.
- Lights: Emission added to the material's BSDF; for a one-sided pathcl light a Mix shader driven by
  Geometry > Backfacing keeps only the BSDF on the back side (Cycles' mesh lights otherwise emit on both
  sides).
- World: black. Meshes: flat shaded; spheres are tessellated (icosphere level 5; an approximation).
"""
import json
import os

from scene_model import UnsupportedMaterial, camera_frame, is_closed, refuse, shape_triangles, write_ply

RR_DEPTH_PATHCL = 3

REFUSED = {
    "rough_conductor": "the GGX Glossy BSDF of Blender 3.4 (alpha = Roughness^2, as pathcl) has no conductor Fresnel"
                       " term (its Color is a constant reflectance) and the separable masking-shadowing"
                       " G1(wi) G1(wo), where pathcl's is the height-correlated 1 / (1 + Lambda(wi) + Lambda(wo));"
                       " a smooth metal can be a mirror",
    "oren_nayar": "the Diffuse BSDF with a roughness is Fujii's improved Oren-Nayar model, not pbrt-v3's qualitative"
                  " one",
    "phong": "Cycles has no normalised modified Phong BSDF",
    "plastic": "no node can give the base pathcl's (1 - F(cos theta_i)) factor of the light direction",
    "thin_dielectric": "no node reflects R' = 2R / (1 + R) and passes the rest straight through",
}


def material_data(m):
    """What the generated script needs to build material M (scene_model.Material) in Cycles."""
    if m.type == "mirror" and m.eta is not None:
        refuse(m, "Cycles", "its Sharp Glossy BSDF reflects a constant colour, not a metal's Fresnel term (eta, k)")
    if m.type in ("diffuse", "mirror"):
        return {"type": m.type, "reflectance": list(m.reflectance)}
    if m.type == "dielectric":
        return {"type": m.type, "ior": m.ior, "transmittance": list(m.transmittance)}
    refuse(m, "Cycles", REFUSED[m.type])


def max_bounces(pathcl_max_depth):
    if pathcl_max_depth < 1:
        raise ValueError("Cycles cannot render max_depth 0 (emitters only)")
    return pathcl_max_depth - 1


def min_light_bounces():
    return RR_DEPTH_PATHCL - 1


def camera_matrix(cam):
    """Blender camera world matrix, row-major 4x4."""
    forward, right, up = camera_frame(cam)
    back = tuple(-c for c in forward)
    return [[right[r], up[r], back[r], cam.position[r]] for r in range(3)] + [[0.0, 0.0, 0.0, 1.0]]


def scene_data(scene):
    """The JSON the generated script reads (meshes are referenced by PLY path, relative to it)."""
    import math
    cam = scene.camera
    shapes = []
    for i, s in enumerate(scene.shapes):
        if s.sphere is None and not s.triangles:
            continue
        m = scene.materials[s.material]
        if m.type == "dielectric" and not is_closed(s):
            raise UnsupportedMaterial(
                "%s: %s (material %s): Cycles cannot render pathcl's dielectric exactly on an open or inconsistently"
                " oriented mesh: Cycles does not scale radiance by (n_i / n_t)^2 on refraction as pathcl does, and the"
                " factors cancel only on closed objects" % (scene.path, s.name, m.name))
        shapes.append({"name": s.name, "ply": "meshes/shape%d.ply" % i, "material": s.material,
                       "emission": list(s.emission), "two_sided": s.two_sided})
    return {
        "camera": {"matrix": camera_matrix(cam), "angle_y": math.radians(cam.fov_y_degrees),
                   "width": cam.width, "height": cam.height},
        "materials": {m.name: material_data(m) for m in scene.used_materials()},
        "shapes": shapes,
        "max_bounces": max_bounces(scene.max_depth),
        "min_light_bounces": min_light_bounces(),
        "spp": scene.spp,
        "seed": scene.seed,
    }


def export(scene, out_dir):
    os.makedirs(os.path.join(out_dir, "meshes"), exist_ok=True)
    data = scene_data(scene)
    by_name = {s.name: s for s in scene.shapes}
    for entry in data["shapes"]:
        positions, triangles = shape_triangles(by_name[entry["name"]])
        write_ply(os.path.join(out_dir, entry["ply"]), positions, triangles)
    with open(os.path.join(out_dir, "cycles.json"), "w") as f:
        json.dump(data, f, indent=1)
    path = os.path.join(out_dir, "cycles_scene.py")
    with open(path, "w") as f:
        f.write(BLENDER_SCRIPT)
    return path


# The script Blender runs. Uses only bpy and the standard library (Debian's Blender has no numpy).
BLENDER_SCRIPT = r'''"""Generated by pathcl scripts/bench/export_cycles.py: builds the scene in Cycles and renders it."""
import argparse
import json
import os
import sys
import time

from array import array
import struct

import bpy
from mathutils import Matrix

T0 = time.time()
HERE = os.path.dirname(os.path.abspath(__file__))


def read_ply(path):
    with open(path, "rb") as f:
        data = f.read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode("ascii").splitlines()
    nv = int(next(l for l in header if l.startswith("element vertex")).split()[2])
    nf = int(next(l for l in header if l.startswith("element face")).split()[2])
    pos = array("f", data[end:end + 12 * nv])
    idx = array("i")
    for _, a, b, c in struct.iter_unpack("<B3i", data[end + 12 * nv:end + 12 * nv + 13 * nf]):
        idx.extend((a, b, c))
    return pos, idx


def surface(nt, m):
    """The output socket of pathcl material M built from nodes (export_cycles.py gives the mapping)."""
    if m["type"] == "diffuse":
        diffuse = nt.nodes.new("ShaderNodeBsdfDiffuse")
        diffuse.inputs["Color"].default_value = (*m["reflectance"], 1.0)
        diffuse.inputs["Roughness"].default_value = 0.0
        return diffuse.outputs["BSDF"]
    if m["type"] == "mirror":
        mirror = nt.nodes.new("ShaderNodeBsdfGlossy")
        mirror.distribution = "SHARP"
        mirror.inputs["Color"].default_value = (*m["reflectance"], 1.0)
        return mirror.outputs["BSDF"]
    if m["type"] == "dielectric":
        fresnel = nt.nodes.new("ShaderNodeFresnel")
        fresnel.inputs["IOR"].default_value = m["ior"]
        refraction = nt.nodes.new("ShaderNodeBsdfRefraction")
        refraction.distribution = "SHARP"
        refraction.inputs["Color"].default_value = (*m["transmittance"], 1.0)
        refraction.inputs["IOR"].default_value = m["ior"]
        reflection = nt.nodes.new("ShaderNodeBsdfGlossy")
        reflection.distribution = "SHARP"
        reflection.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
        mix = nt.nodes.new("ShaderNodeMixShader")
        nt.links.new(fresnel.outputs["Fac"], mix.inputs["Fac"])
        nt.links.new(refraction.outputs["BSDF"], mix.inputs[1])
        nt.links.new(reflection.outputs["BSDF"], mix.inputs[2])
        return mix.outputs["Shader"]
    raise ValueError("unknown material type " + m["type"])


def material(name, m, emission, two_sided):
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    nt = mat.node_tree
    nt.nodes.clear()
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    bsdf = surface(nt, m)
    if max(emission) <= 0:
        nt.links.new(bsdf, out.inputs["Surface"])
        return mat
    strength = max(emission)
    emit = nt.nodes.new("ShaderNodeEmission")
    emit.inputs["Color"].default_value = (*[c / strength for c in emission], 1.0)
    emit.inputs["Strength"].default_value = strength
    front = nt.nodes.new("ShaderNodeAddShader")
    nt.links.new(bsdf, front.inputs[0])
    nt.links.new(emit.outputs["Emission"], front.inputs[1])
    if two_sided:
        nt.links.new(front.outputs["Shader"], out.inputs["Surface"])
        return mat
    back = surface(nt, m)
    geometry = nt.nodes.new("ShaderNodeNewGeometry")
    mix = nt.nodes.new("ShaderNodeMixShader")
    nt.links.new(geometry.outputs["Backfacing"], mix.inputs["Fac"])
    nt.links.new(front.outputs["Shader"], mix.inputs[1])
    nt.links.new(back, mix.inputs[2])
    nt.links.new(mix.outputs["Shader"], out.inputs["Surface"])
    return mat


def build(data, threads):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    sc = bpy.context.scene
    sc.render.engine = "CYCLES"
    c = sc.cycles
    c.device = "CPU"
    c.use_adaptive_sampling = False
    c.use_denoising = False
    if hasattr(c, "use_preview_denoising"):
        c.use_preview_denoising = False
    c.max_bounces = c.diffuse_bounces = data["max_bounces"]
    c.glossy_bounces = c.transmission_bounces = data["max_bounces"]
    c.volume_bounces = 0
    c.transparent_max_bounces = 0
    c.min_light_bounces = data["min_light_bounces"]
    c.min_transparent_bounces = 0
    c.sample_clamp_direct = 0.0
    c.sample_clamp_indirect = 0.0
    c.light_sampling_threshold = 0.0
    if hasattr(c, "use_light_tree"):
        c.use_light_tree = False
    c.blur_glossy = 0.0
    c.caustics_reflective = True
    c.caustics_refractive = True
    c.pixel_filter_type = "BOX"
    c.filter_width = 1.0
    sc.render.resolution_x = data["camera"]["width"]
    sc.render.resolution_y = data["camera"]["height"]
    sc.render.resolution_percentage = 100
    sc.render.film_transparent = False
    sc.render.dither_intensity = 0.0
    sc.render.use_persistent_data = True
    if threads:
        sc.render.threads_mode = "FIXED"
        sc.render.threads = threads
    sc.view_settings.view_transform = "Standard"
    sc.view_settings.look = "None"
    sc.view_settings.exposure = 0.0
    sc.view_settings.gamma = 1.0
    s = sc.render.image_settings
    s.file_format = "OPEN_EXR"
    s.color_mode = "RGB"
    s.color_depth = "32"
    s.exr_codec = "ZIP"

    world = bpy.data.worlds.new("black")
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Color"].default_value = (0, 0, 0, 1)
    world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.0
    sc.world = world

    cam_data = bpy.data.cameras.new("camera")
    cam_data.sensor_fit = "VERTICAL"
    cam_data.angle_y = data["camera"]["angle_y"]
    cam_data.clip_start = 1e-6
    cam_data.clip_end = 1e12
    cam = bpy.data.objects.new("camera", cam_data)
    cam.matrix_world = Matrix(data["camera"]["matrix"])
    sc.collection.objects.link(cam)
    sc.camera = cam

    for s in data["shapes"]:
        mat = material(s["name"], data["materials"][s["material"]], s["emission"], s["two_sided"])
        pos, idx = read_ply(os.path.join(HERE, s["ply"]))
        nf = len(idx) // 3
        me = bpy.data.meshes.new(s["name"])
        me.vertices.add(len(pos) // 3)
        me.vertices.foreach_set("co", pos)
        me.loops.add(len(idx))
        me.loops.foreach_set("vertex_index", idx)
        me.polygons.add(nf)
        me.polygons.foreach_set("loop_start", array("i", range(0, 3 * nf, 3)))
        me.polygons.foreach_set("loop_total", array("i", [3]) * nf)
        me.polygons.foreach_set("use_smooth", [False] * nf)
        me.update()
        me.materials.append(mat)
        ob = bpy.data.objects.new(s["name"], me)
        sc.collection.objects.link(ob)
    return sc


def main():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    ap = argparse.ArgumentParser()
    ap.add_argument("--spp", type=int)
    ap.add_argument("--spp-series", help="comma-separated sample counts, one render each")
    ap.add_argument("--seed", type=int)
    ap.add_argument("--seeds", help="comma-separated seeds, one render each (with --spp)")
    ap.add_argument("--time", type=float, default=0.0, help="Cycles time limit in seconds (0: none)")
    ap.add_argument("--threads", type=int, default=0)
    ap.add_argument("--out", required=True, help="output EXR; {spp} and {seed} are replaced")
    args = ap.parse_args(argv)
    with open(os.path.join(HERE, "cycles.json")) as f:
        data = json.load(f)
    sc = build(data, args.threads)
    setup = time.time() - T0
    series = [int(x) for x in args.spp_series.split(",")] if args.spp_series else [args.spp or data["spp"]]
    seeds = [int(x) for x in args.seeds.split(",")] if args.seeds else [args.seed if args.seed is not None else data["seed"]]
    for seed in seeds:
        for spp in series:
            sc.cycles.samples = spp if not args.time else 1 << 24
            sc.cycles.time_limit = args.time
            sc.cycles.seed = seed
            out = args.out.replace("{spp}", str(spp)).replace("{seed}", str(seed))
            sc.render.filepath = out
            t = time.time()
            bpy.ops.render.render(write_still=True)
            seconds = time.time() - t
            print("PATHCL_BENCH " + json.dumps({"spp": spp, "seed": seed, "setup_seconds": setup,
                                                 "render_seconds": seconds, "out": out,
                                                 "blender": bpy.app.version_string}), flush=True)


main()
'''
