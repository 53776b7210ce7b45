"""Exports a pathcl scene (scene_model.Scene) to a Mitsuba 3 XML scene with binary PLY meshes.

Mapping:
- Camera: `perspective` with `fov_axis` y, `to_world` look-at (Mitsuba's frame puts +x on the image's
  left, which equals pathcl's right-handed `right` on the image's right), box reconstruction filter of
  radius 0.5 (a pixel wide, like pathcl's uniform jitter in the pixel), `independent` sampler.
- Depth: Mitsuba's `max_depth` counts path segments (1 = emitters seen directly), pathcl's counts
  scattering events (0 = emitters seen directly), so max_depth = pathcl + 1. Russian roulette starts in
  pathcl once more than 3 scattering events were made (depth + 1 > 3); Mitsuba's starts when its depth
  counter (scattering events so far) is >= rr_depth, so rr_depth = 4. Mitsuba caps the survival
  probability at 0.95 where pathcl uses min(1, max throughput): unbiased either way, the variance differs.
- Materials: pathcl's diffuse reflects on both sides; Mitsuba's `diffuse` only on the front, so it is
  wrapped in `twosided`.
- Lights: `area` emitters emit on the front side (the counter-clockwise side, as in pathcl); a
  `two_sided` pathcl light becomes two shapes, the second with reversed winding.
- Meshes: `ply` with `face_normals` (flat shading, as pathcl without `smooth`); spheres are analytic.
"""
import os
from xml.sax.saxutils import quoteattr

from scene_model import camera_frame, write_ply

RR_DEPTH_PATHCL = 3


def max_depth(pathcl_max_depth):
    return pathcl_max_depth + 1


def rr_depth():
    return RR_DEPTH_PATHCL + 1


def _vec(v):
    return "%.9g, %.9g, %.9g" % tuple(v)


def export(scene, out_dir, name="scene"):
    """Writes OUT_DIR/NAME.xml (parameters $spp, $seed, $max_depth, $timeout) and OUT_DIR/meshes/*.ply."""
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
         '    <sampler type="independent">',
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
    for m in scene.materials.values():
        x += ['  <bsdf type="twosided" id=%s>' % quoteattr("mat-" + m.name),
              '    <bsdf type="diffuse"><rgb name="reflectance" value="%s"/></bsdf>' % _vec(m.reflectance),
              '  </bsdf>']
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
