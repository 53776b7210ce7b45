/* The scene's device arrays, gathered once per work item so that functions take one argument for them. */
#ifndef PATHCL_SCENE_CL
#define PATHCL_SCENE_CL

typedef struct {
  __constant const SceneHeader* h;
  __global const Bvh4Node* nodes;
  __global const Primitive* prims;     /* BVH leaf order */
  __global const PrimShading* shading; /* scene order */
  __global const float4* normals;      /* 3 per primitive (smooth shapes) */
  __global const float4* uvs;          /* 2 per primitive, when textures are used: triangle (u0, v0, u1, v1),
                                          (u2, v2, -, -); sphere (x axis, handedness), (y axis, -) */
  __global const Material* materials;
  __global const Light* lights;
  __global const float* light_cdf;
  __global const Texture* textures;
  __global const float4* texels;
  __global const float* env_dist;      /* environment.cl */
} SceneData;

#endif
