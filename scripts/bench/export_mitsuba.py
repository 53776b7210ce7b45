"""Exports a pathcl scene (scene_model.Scene) to a Mitsuba 3 XML scene with binary PLY meshes.

Mapping:
- Camera: `perspective` with `fov_axis` y, `to_world` look-at (Mitsuba's frame puts +x on the image's
  left, which equals pathcl's right-handed `right` on the image's right), box reconstruction filter of
  radius 0.5 (a pixel wide, like pathcl's uniform jitter in the pixel), `multijitter` sampler (each
  renderer gets its best sampler: on the Cornell box at 64 spp Mitsuba's relMSE was 3.05e-3 with
  `independent`, 1.57e-3 with `multijitter` and 1.71e-3 with `ldsampler`, at 0.85x the speed).
- Depth: Mitsuba's `max_depth` counts path segments (1 = emitters seen directly), pathcl's counts
  scattering events (0 = emitters seen directly), so max_depth = pathcl + 1. Russian roulette starts in
  pathcl once more than 3 scattering events were made (depth + 1 > 3); Mitsuba's starts when its depth
  counter (scattering events so far) is >= rr_depth, so rr_depth = 4. Mitsuba caps the survival
  probability at 0.95 where pathcl uses min(1, max throughput): unbiased either way, the variance differs.
- Materials (only those with the same BSDF model; the others are refused, naming the material):
  - `diffuse`: `diffuse`. pathcl's reflects on both sides, Mitsuba's only on the front, so it is wrapped
    in `twosided`.
  - `mirror`: `conductor` with material "none" (complex index 0 + 1i: Fresnel reflectance exactly 1)
    and `specular_reflectance` = reflectance, in `twosided`; a mirror with `eta` and `k` (a smooth metal):
    `conductor` with that eta and k.
  - `thin_dielectric`: `thindielectric` (int_ior = ior, ext_ior = 1, `specular_transmittance`), in `twosided`.
  - `dielectric`: `dielectric` with int_ior = ior and ext_ior = 1 (Mitsuba's default ext_ior is air,
    1.000277), `specular_transmittance` = transmittance, reflection untinted. Exact Fresnel, the normal's
    side is the outside (the counter-clockwise side, as pathcl's front side), and both scale radiance by
    (n_i / n_t)^2 on refraction. Not in `twosided` (the two sides differ).
  - `rough_conductor` is refused: `roughconductor` with distribution ggx has the same D, alpha and
    conductor Fresnel term, but its masking-shadowing is the separable G1(wi) G1(wo), pathcl's the
    height-correlated 1 / (1 + Lambda(wi) + Lambda(wo)). oren_nayar, phong and plastic are refused too.
- Lights: `area` emitters emit on the front side (the counter-clockwise side, as in pathcl); a
  `two_sided` pathcl light becomes two shapes, the second with reversed winding.
- Meshes: `ply` with `face_normals` (flat shading, as pathcl without `smooth`); spheres are analytic.
"""
import os
from xml.sax.saxutils import quoteattr

from scene_model import camera_frame, refuse, write_ply

RR_DEPTH_PATHCL = 3


def max_depth(pathcl_max_depth):
    return pathcl_max_depth + 1


def rr_depth():
    return RR_DEPTH_PATHCL + 1


def _vec(v):
    return "%.9g, %.9g, %.9g" % tuple(v)


REFUSED = {
    "rough_conductor": "its roughconductor (ggx) has the same distribution, alpha and conductor Fresnel term, but"
                       " the separable masking-shadowing G1(wi) G1(wo), where pathcl's is the height-correlated"
                       " 1 / (1 + Lambda(wi) + Lambda(wo))",
    "oren_nayar": "Mitsuba 3 has no Oren-Nayar BSDF",
    "phong": "Mitsuba 3 has no normalised modified Phong BSDF",
    "plastic": "its plastic and roughplastic scale the base by 1 / ior^2 and return the light reflected inside"
               " the coat; pathcl's plastic does neither",
}


def bsdf_lines(m):
    """The <bsdf> element of material M (scene_model.Material), id "mat-NAME"."""
    mid = quoteattr("mat-" + m.name)
    if m.type == "diffuse":
        return ['  <bsdf type="twosided" id=%s>' % mid,
                '    <bsdf type="diffuse"><rgb name="reflectance" value="%s"/></bsdf>' % _vec(m.reflectance),
                '  </bsdf>']
    if m.type == "mirror":
        # A plain mirror: Mitsuba's perfect conductor; a metal mirror: its complex index (the same Fresnel term).
        index = (['      <string name="material" value="none"/>'] if m.eta is None else
                 ['      <rgb name="eta" value="%s"/>' % _vec(m.eta), '      <rgb name="k" value="%s"/>' % _vec(m.k)])
        return (['  <bsdf type="twosided" id=%s>' % mid, '    <bsdf type="conductor">'] + index +
                ['      <rgb name="specular_reflectance" value="%s"/>' % _vec(m.reflectance),
                 '    </bsdf>',
                 '  </bsdf>'])
    if m.type == "thin_dielectric":  # the same R' = 2R / (1 + R) and straight transmission
        return ['  <bsdf type="twosided" id=%s>' % mid,
                '    <bsdf type="thindielectric">',
                '      <float name="int_ior" value="%.9g"/>' % m.ior,
                '      <float name="ext_ior" value="1"/>',
                '      <rgb name="specular_transmittance" value="%s"/>' % _vec(m.transmittance),
                '    </bsdf>',
                '  </bsdf>']
    if m.type == "dielectric":
        return ['  <bsdf type="dielectric" id=%s>' % mid,
                '    <float name="int_ior" value="%.9g"/>' % m.ior,
                '    <float name="ext_ior" value="1"/>',
                '    <rgb name="specular_transmittance" value="%s"/>' % _vec(m.transmittance),
                '  </bsdf>']
    refuse(m, "Mitsuba", REFUSED[m.type])


def export(scene, out_dir, name="scene", sampler="multijitter"):
    """Writes OUT_DIR/NAME.xml (parameters $spp, $seed, $max_depth, $timeout) and OUT_DIR/meshes/*.ply.
    sampler: Mitsuba's sampler plugin (scripts/bench/lanes compares samples/s with `independent`)."""
    os.makedirs(os.path.join(out_dir, "meshes"), exist_ok=True)
    cam = scene.camera
    forward, right, up = camera_frame(cam)
    x = ['<scene version="3.0.0">',
         '  <default name="spp" value="%d"/>' % scene.spp,
         '  <default name="seed" value="%d"/>' % scene.seed,
         '  <default name="max_depth" value="%d"/>' % max_depth(scene.max_depth),
         '  <default name="timeout" value="-1"/>',
         '  <integrator type="path">',
         '    <integer name="max_depth" value="$max_depth"/>',
         '    <integer name="rr_depth" value="%d"/>' % rr_depth(),
         '    <float name="timeout" value="$timeout"/>',
         '  </integrator>',
         '  <sensor type="perspective">',
         '    <string name="fov_axis" value="y"/>',
         '    <float name="fov" value="%.9g"/>' % cam.fov_y_degrees,
         '    <float name="near_clip" value="%.9g"/>' % 1e-4,
         '    <float name="far_clip" value="%.9g"/>' % 1e30,
         '    <transform name="to_world">',
         '      <lookat origin="%s" target="%s" up="%s"/>' % (_vec(cam.position), _vec(cam.look_at), _vec(up)),
         '    </transform>',
         '    <sampler type=%s>' % quoteattr(sampler),
         '      <integer name="sample_count" value="$spp"/>',
         '      <integer name="seed" value="$seed"/>',
         '    </sampler>',
         '    <film type="hdrfilm">',
         '      <integer name="width" value="%d"/>' % cam.width,
         '      <integer name="height" value="%d"/>' % cam.height,
         '      <string name="pixel_format" value="rgb"/>',
         '      <string name="component_format" value="float32"/>',
         '      <rfilter type="box"/>',
         '    </film>',
         '  </sensor>']
    for m in scene.used_materials():
        x += bsdf_lines(m)
    for i, s in enumerate(scene.shapes):
        emitter = ('    <emitter type="area"><rgb name="radiance" value="%s"/></emitter>' % _vec(s.emission)
                   if s.is_emitter else None)
        if s.sphere is not None:
            cx, cy, cz, r, flip = s.sphere
            x += ['  <shape type="sphere">',
                  '    <point name="center" value="%s"/>' % _vec((cx, cy, cz)),
                  '    <float name="radius" value="%.9g"/>' % r,
                  '    <boolean name="flip_normals" value="%s"/>' % ("true" if flip else "false"),
                  '    <ref id=%s/>' % quoteattr("mat-" + s.material)]
            x += [emitter] if emitter else []
            x += ['  </shape>']
            continue
        if not s.triangles:
            continue
        sides = [False, True] if (s.is_emitter and s.two_sided) else [False]
        for flip in sides:
            ply = "meshes/shape%d%s.ply" % (i, "-back" if flip else "")
            write_ply(os.path.join(out_dir, ply), s.positions, s.triangles, flip)
            x += ['  <shape type="ply" id=%s>' % quoteattr(s.name + ("-back" if flip else "")),
                  '    <string name="filename" value=%s/>' % quoteattr(ply),
                  '    <boolean name="face_normals" value="true"/>',
                  '    <ref id=%s/>' % quoteattr("mat-" + s.material)]
            x += [emitter] if emitter else []
            x += ['  </shape>']
    x.append('</scene>')
    path = os.path.join(out_dir, name + ".xml")
    with open(path, "w") as f:
        f.write("\n".join(x) + "\n")
    return path
