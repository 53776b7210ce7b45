// Flattening a scene description into the device scene (scene/device_scene.h).
#pragma once
#include <cstdint>

#include "scene/device_scene.h"
#include "scene/scene_description.h"

// Flattens the scene: primitives in scene order (shapes in file order, triangles of a mesh in mesh
// order; then each instanced mesh's, stored once in its own coordinates), a BVH over the rest of the
// scene and one per instanced mesh, the instance table and its BVH (kernels/intersect.cl), the light distribution (proportional to power), the camera basis; every
// position relative to `origin`, converted to float only after that subtraction. Throws SceneError when
// geometry lies farther than kMaxSceneExtent from the origin. layouts: the BVH layouts to build
// (kBvhLayout4, 8, 16; at least one).
DeviceScene build_device_scene(const SceneDescription& scene, DeviceOrigin origin = DeviceOrigin::camera,
                               Instancing instancing = Instancing::keep, uint32_t layouts = kBvhLayoutsAll);

// The same, but moves the texels of scene's textures into the device scene instead of copying them
// (each TextureImage keeps its size and format and loses its words), so that the host holds them once.
DeviceScene build_device_scene_taking_texels(SceneDescription& scene, DeviceOrigin origin = DeviceOrigin::camera,
                                             Instancing instancing = Instancing::keep,
                                             uint32_t layouts = kBvhLayoutsAll);

// Geometry of a scene-order primitive as the device sees it (world minus DeviceScene::origin), for tests
// and ray generation.
Primitive scene_primitive(const DeviceScene& scene, uint32_t prim_index);
