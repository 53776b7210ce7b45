/* Opens a lane template (a file under templates/: kernel_program.cpp expands it at every #include, where
 * other files are expanded once): the types of width PC_LANE_W (1, 8 or 16 lanes; exact_math.cl also 2, 3
 * and 4), which the includer defines before each include, under the names the template is written with:
 *   F, I, U                float, int and uint (width 1) or their vectors of the width
 *   V3                     lanes of 3-vectors by component: lane3f (float3), lane3f8 or lane3f16 (1, 8, 16)
 *   convert_F, convert_I   convert_float, convert_int of the width
 *   as_F, as_I, as_U       as_float, as_int, as_uint of the width
 *   PC_LANE_NAME(x)        the name x followed by the width (RayPacket8)
 * templates/lane_width_end.h closes it. */
#ifndef PC_LANE_NAME
#define PC_LANE_NAME(x) PC_LANE_NAME_(x, PC_LANE_W)
#define PC_LANE_NAME_(x, w) PC_LANE_NAME__(x, w)
#define PC_LANE_NAME__(x, w) x##w
#endif
#if PC_LANE_W == 1
#define F float
#define I int
#define U uint
#define V3 lane3f
#define convert_F convert_float
#define convert_I convert_int
#define as_F as_float
#define as_I as_int
#define as_U as_uint
#elif PC_LANE_W == 2 || PC_LANE_W == 3 || PC_LANE_W == 4
#if PC_LANE_W == 2
#define F float2
#define I int2
#define U uint2
#define convert_F convert_float2
#define convert_I convert_int2
#define as_F as_float2
#define as_I as_int2
#define as_U as_uint2
#elif PC_LANE_W == 3
#define F float3
#define I int3
#define U uint3
#define convert_F convert_float3
#define convert_I convert_int3
#define as_F as_float3
#define as_I as_int3
#define as_U as_uint3
#else
#define F float4
#define I int4
#define U uint4
#define convert_F convert_float4
#define convert_I convert_int4
#define as_F as_float4
#define as_I as_int4
#define as_U as_uint4
#endif
#elif PC_LANE_W == 8
#define F float8
#define I int8
#define U uint8
#define V3 lane3f8
#define convert_F convert_float8
#define convert_I convert_int8
#define as_F as_float8
#define as_I as_int8
#define as_U as_uint8
#elif PC_LANE_W == 16
#define F float16
#define I int16
#define U uint16
#define V3 lane3f16
#define convert_F convert_float16
#define convert_I convert_int16
#define as_F as_float16
#define as_I as_int16
#define as_U as_uint16
#else
#error "PC_LANE_W: 1, 8 or 16 (or 2, 3, 4)"
#endif
