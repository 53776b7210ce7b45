/* The film's layers, shared byte for byte by the host and the kernels (the rules of types.h). A film is a
 * list of named layers (runtime/film_layout.h), each a plane of `words` 32-bit words per pixel at a word
 * offset in one film buffer, of one of two kinds:
 *   ordered:     float sums that a pixel's samples are added to in sample order, by the work item that
 *                owns the pixel (the path integrator's accumulators, every AOV); a unit's pixels are copied
 *                into the film, never added, so no float is ever summed in an order that timing decides
 *   commutative: 64-bit fixed-point integer sums (two words, low first) that any work item adds to with
 *                integer atomics (light tracing's and BDPT's splats): a unit covers the whole image and is
 *                added to the film in integers, the same bits in any order
 * The technique's own layers come first (offset 0: its render kernel takes the film buffer as it is), the
 * AOVs after them. Needs shared/types.h first. */
#ifndef PATHCL_SHARED_FILM_TYPES_H
#define PATHCL_SHARED_FILM_TYPES_H

#define PC_LAYER_ORDERED 0u
#define PC_LAYER_COMMUTATIVE 1u

/* The path integrator's accumulators: three float4 a pixel, the sums of the even-numbered and of the
 * odd-numbered samples (w counts them) and the sum of squares. */
#define PC_RADIANCE_WORDS 12u

/* Arbitrary output variables (`--aov`), one ordered layer each, computed from the camera rays of the
 * beauty's samples (kernels/aov.cl): sums over a pixel's samples in order (the pixel filter's weighting,
 * as the beauty's), except the ids, which are those of the pixel's sample 0. Bit PC_AOV_* of a mask. */
#define PC_AOV_ALBEDO 0u      /* 3: reflectance at the first non-delta hit, times the delta chain's throughput */
#define PC_AOV_NORMAL 1u      /* 3: world-space shading normal there */
#define PC_AOV_DEPTH 2u       /* 1: distance along the camera ray to the first hit */
#define PC_AOV_POSITION 3u    /* 3: world-space position of the first hit */
#define PC_AOV_UV 4u          /* 2: texture coordinates of the first hit */
#define PC_AOV_SHAPE_ID 5u    /* 1 (uint): the first hit's shape index + 1, 0 where the ray escapes */
#define PC_AOV_MATERIAL_ID 6u /* 1 (uint): the first hit's material index + 1, 0 where the ray escapes */
#define PC_AOV_COUNT 7u

/* Where the AOV pass writes: the word offset of each AOV's plane in the film buffer (PC_INVALID where it
 * is not rendered), and the world position of the device coordinates' origin (the camera's: positions on
 * the device are relative to it). origin (16) + offset (8 x 4) = 48 bytes. */
typedef struct {
  pc_float4 origin;
  pc_uint offset[8];
} AovHeader;

#define PC_FILM_LAYOUT_STRUCTS(X) X(AovHeader)
#define PC_FILM_LAYOUT_FIELDS(X) X(AovHeader, origin) X(AovHeader, offset)

#ifndef __OPENCL_VERSION__
static_assert(sizeof(AovHeader) == 48, "AovHeader is 48 bytes");
#endif

#endif
