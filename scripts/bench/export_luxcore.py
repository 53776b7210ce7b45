"""Exports a pathcl scene (scene_model.Scene) to LuxCoreRender properties: OUT/scene.scn, OUT/render.cfg
and OUT/meshes/*.ply.

Mapping:
- Camera: `perspective` look-at with `fieldofview` = fov_y and an explicit `screenwindow` of
  [-aspect, aspect, -1, 1], so the vertical field of view is pathcl's whatever the aspect ratio (LuxCore
  otherwise applies the field of view to one axis chosen by the aspect). pyluxcore 2.11 shows film row r
  what the screen window puts at row r - 1 (measured on the Cornell box: the light's lower edge one row
  lower than in pathcl, Mitsuba and Cycles, columns unchanged), so the window is moved down by one pixel
  (2 / height in screen units) to compensate (ROW_OFFSET_PIXELS). Film filter: BOX of width 0.5
  (LuxCore's filter width is a radius: one pixel wide in all). Sampler: RANDOM (on the Cornell box at
  64 spp SOBOL had relMSE 1.67e-3 against RANDOM's 2.69e-3 but took 1.9x the time, so RANDOM is faster to an error).
- Depth: LuxCore's `path.pathdepth.total` counts scattering events like pathcl's max_depth (1 = direct
  light only), so it is the same number, as are the diffuse, glossy and specular limits. Russian
  roulette: `path.russianroulette.depth` 4 (LuxCore starts at that path depth, counted from 1 at the
  first scattering, so at the 4th scattering event, as pathcl) with a cap (lower bound on the survival
  probability) of 0.
- Off: clamping, light tracing (hybrid back/forward), the photon GI cache.
- Materials (only those with the same BSDF model; the others are refused, naming the material):
  - `diffuse`: `matte` (Lambertian, both sides).
  - `mirror`: `mirror` with kr = reflectance (a delta reflection of weight kr, no Fresnel, both sides).
  - `dielectric`: `glass` with interiorior = ior, exteriorior = 1, kr = 1, kt = transmittance: the exact
    dielectric Fresnel term (FresnelTexture::CauchyEvaluate), the front (counter-clockwise) side outside,
    and camera paths scaled by (n_i / n_t)^2 on refraction as in pathcl. LuxCore chooses reflection or
    refraction with probability 1/2 each instead of F and 1 - F: the same image, other noise.
  - `rough_conductor` is refused: `metal2` has GGX's distribution (alpha^2 = uroughness vroughness, so
    pathcl's alpha = roughness^2 would be u = v = alpha) but Schlick's approximation of the masking term,
    cos / (cos (1 - alpha^2) + alpha^2) per direction, not Smith's. oren_nayar, phong and plastic are
    refused too.
- Lights: `emission` with gain 1 on a copy of the material; LuxCore's triangle lights emit on the front
  (counter-clockwise) side; a two-sided pathcl light gets a second, reversed copy. Light strategy: POWER
  (pathcl picks lights in proportion to power). Spheres are tessellated (icosphere level 5).
"""
import os

from scene_model import camera_frame, refuse, shape_triangles, write_ply

RR_DEPTH_PATHCL = 3
ROW_OFFSET_PIXELS = 1


def path_depth(pathcl_max_depth):
    return pathcl_max_depth


def rr_depth():
    return RR_DEPTH_PATHCL + 1


def _vec(v):
    return "%.9g %.9g %.9g" % tuple(v)


REFUSED = {
    "rough_conductor": "its metal2 has the GGX distribution (alpha^2 = uroughness * vroughness) but Schlick's"
                       " approximation of the masking-shadowing term, cos / (cos (1 - alpha^2) + alpha^2) per"
                       " direction, not the height-correlated Smith term of pathcl",
    "oren_nayar": "its roughmatte looks like the same qualitative Oren-Nayar formula (sigma in radians), but that"
                  " mapping has not been checked against pathcl yet",
    "phong": "LuxCore has no normalised modified Phong BSDF",
    "thin_dielectric": "its archglass has not been checked against pathcl's thin dielectric yet",
    "plastic": "its glossy2 is Schlick's coating model (Schlick's Fresnel approximation and distribution), not"
               " pathcl's exact-Fresnel coat",
}


def material_lines(m, name=None):
    """The .scn lines of material M (scene_model.Material), named NAME (default: its own)."""
    p = "scene.materials.%s." % (name or m.name)
    if m.type == "diffuse":
        return [p + 'type = "matte"', p + "kd = " + _vec(m.reflectance)]
    if m.type == "mirror":
        if m.eta is not None:
            refuse(m, "LuxCore", "its mirror has no Fresnel term (a metal's eta and k): metal2 is not smooth")
        return [p + 'type = "mirror"', p + "kr = " + _vec(m.reflectance)]
    if m.type == "dielectric":
        return [p + 'type = "glass"', p + "kr = 1 1 1", p + "kt = " + _vec(m.transmittance),
                p + "interiorior = %.9g" % m.ior, p + "exteriorior = 1"]
    refuse(m, "LuxCore", REFUSED[m.type])


def scene_properties(scene):
    """The .scn lines and the PLY files to write: ([line], [(ply_path, positions, triangles, flip)])."""
    cam = scene.camera
    forward, right, up = camera_frame(cam)
    aspect = cam.width / cam.height
    shift = 2.0 * ROW_OFFSET_PIXELS / cam.height
    lines = ['scene.camera.type = "perspective"',
             'scene.camera.lookat.orig = %s' % _vec(cam.position),
             'scene.camera.lookat.target = %s' % _vec(cam.look_at),
             'scene.camera.up = %s' % _vec(up),
             'scene.camera.fieldofview = %.9g' % cam.fov_y_degrees,
             'scene.camera.screenwindow = %.9g %.9g %.9g %.9g' % (-aspect, aspect, -1 - shift, 1 - shift),
             'scene.camera.cliphither = 1e-06',
             'scene.camera.clipyon = 1e+30']
    for m in scene.used_materials():
        lines += material_lines(m)
    plys = []
    for i, s in enumerate(scene.shapes):
        if s.sphere is None and not s.triangles:
            continue
        mat = s.material
        if s.is_emitter:  # one emitting copy of the material per light colour
            mat = "%s_emit%d" % (s.material, i)
            lines += material_lines(scene.materials[s.material], mat)
            lines += ['scene.materials.%s.emission = %s' % (mat, _vec(s.emission)),
                      'scene.materials.%s.emission.gain = 1 1 1' % mat,
                      'scene.materials.%s.emission.power = 0' % mat,
                      'scene.materials.%s.emission.efficency = 0' % mat]
        positions, triangles = shape_triangles(s)
        for flip in ([False, True] if (s.is_emitter and s.two_sided) else [False]):
            name = "shape%d%s" % (i, "back" if flip else "")
            ply = "meshes/%s.ply" % name
            plys.append((ply, positions, triangles, flip))
            lines += ['scene.shapes.%s.type = "mesh"' % name,
                      'scene.shapes.%s.ply = "%s"' % (name, ply),
                      'scene.objects.%s.shape = "%s"' % (name, name),
                      'scene.objects.%s.material = "%s"' % (name, mat)]
    return lines, plys


def render_properties(scene, engine="PATHCPU", spp=None, seed=None, halt_time=0, threads=0, opencl_device=None,
                      output="image.exr"):
    """The .cfg lines for ENGINE (PATHCPU or PATHOCL)."""
    cam = scene.camera
    depth = path_depth(scene.max_depth)
    lines = ['renderengine.type = "%s"' % engine,
             'renderengine.seed = %d' % (seed if seed is not None else scene.seed),
             'sampler.type = "RANDOM"',
             'scene.file = "scene.scn"',
             'film.width = %d' % cam.width,
             'film.height = %d' % cam.height,
             'film.filter.type = "BOX"',
             'film.filter.width = 0.5',
             'film.imagepipelines.0.0.type = "NOP"',
             'film.outputs.0.type = "RGB"',
             'film.outputs.0.filename = "%s"' % output,
             'path.pathdepth.total = %d' % depth,
             'path.pathdepth.diffuse = %d' % depth,
             'path.pathdepth.glossy = %d' % depth,
             'path.pathdepth.specular = %d' % depth,
             'path.russianroulette.depth = %d' % rr_depth(),
             'path.russianroulette.cap = 0',
             'path.clamping.variance.maxvalue = 0',
             'path.hybridbackforward.enable = 0',
             'path.photongi.sampler.type = "NONE"',
             'path.photongi.indirect.enabled = 0',
             'path.photongi.caustic.enabled = 0',
             'lightstrategy.type = "POWER"',
             'batch.haltspp = %d' % (spp if spp is not None else scene.spp),
             'batch.halttime = %g' % halt_time]
    if threads:
        lines.append('native.threads.count = %d' % threads)
    if engine == "PATHOCL":
        lines += ['opencl.cpu.use = 1', 'opencl.gpu.use = 0', 'opencl.native.threads.count = 0']
        if opencl_device is not None:
            lines.append('opencl.devices.select = "%s"' % opencl_device)
    return lines


def export(scene, out_dir, engine="PATHCPU"):
    os.makedirs(os.path.join(out_dir, "meshes"), exist_ok=True)
    lines, plys = scene_properties(scene)
    for ply, positions, triangles, flip in plys:
        write_ply(os.path.join(out_dir, ply), positions, triangles, flip)
    with open(os.path.join(out_dir, "scene.scn"), "w") as f:
        f.write("\n".join(lines) + "\n")
    with open(os.path.join(out_dir, "render.cfg"), "w") as f:
        f.write("\n".join(render_properties(scene, engine)) + "\n")
    return os.path.join(out_dir, "render.cfg")


def parse_properties(text):
    """LuxCore property lines as {key: [values]} (for tests; quotes stripped)."""
    props = {}
    for line in text.splitlines():
        if "=" not in line or line.lstrip().startswith("#"):
            continue
        key, value = line.split("=", 1)
        props[key.strip()] = [v.strip('"') for v in value.split()]
    return props
