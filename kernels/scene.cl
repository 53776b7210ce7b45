/* The scene's device arrays, gathered once per work item so that functions take one argument for them.
 * The arrays are PC_SCENE_ARRAYS of shared/types.h; what each holds is written in scene/device_scene.h.
 *   normals: 3 per primitive (smooth shapes)
 *   uvs:     2 per primitive, when textures are used: triangle (u0, v0, u1, v1), (u2, v2, -, -);
 *            sphere (x axis, handedness), (y axis, -)
 *   env_dist: environment.cl */
#ifndef PATHCL_SCENE_CL
#define PATHCL_SCENE_CL

#define PC_SCENE_FIELD(T, name) __global const T* name;
typedef struct {
  __constant const SceneHeader* h;
  PC_SCENE_ARRAYS(PC_SCENE_FIELD)
} SceneData;
#undef PC_SCENE_FIELD

/* The BVH of the layout this program was built for, as trace_bvh's first two arguments: the nodes and
 * the leaf blocks (kernels/intersect.cl), for the 8- and 16-wide layouts both in bvh8 or bvh16; the
 * 4-wide one has none. */
#if PC_BVH_WIDE == 16
#define PC_SCENE_BVH(sc) (__global const Bvh16Node*)(sc)->bvh16, (__global const LeafBlock*)(sc)->bvh16
#elif PC_BVH_WIDE == 8
#define PC_SCENE_BVH(sc) (__global const Bvh8Node*)(sc)->bvh8, (__global const LeafBlock*)(sc)->bvh8
#else
#define PC_SCENE_BVH(sc) (sc)->nodes, (__global const LeafBlock*)(sc)->bvh8
#endif

/* A kernel's first parameters: the header and every scene array (bound by runtime/scene_buffers.h). */
#define PC_SCENE_PARAM(T, name) , __global const T* name
#define PC_SCENE_PARAMS __constant const SceneHeader* h PC_SCENE_ARRAYS(PC_SCENE_PARAM)
/* SceneData from those parameters: SceneData sc = PC_SCENE_DATA; */
#define PC_SCENE_ARG(T, name) , name
#define PC_SCENE_DATA {h PC_SCENE_ARRAYS(PC_SCENE_ARG)}

/* The body of a large kernel is a function of its own (NAME_item, given the SceneData and get_global_id(0)),
 * which the kernel calls. PoCL's CPU driver compiles the kernel function into each of the two work-group
 * launchers it generates besides it: inlined there, the body would be compiled three times (the path
 * program's build took 10 % longer). */
#define PC_KERNEL_BODY PC_OUT_OF_LINE

#endif
