#pragma OPENCL FP_CONTRACT OFF
/* Math functions that give the same bits on every conformant OpenCL implementation (PoCL, Oclgrind, GPU
 * drivers), unlike the builtins, whose precision is implementation-defined.
 *
 * Built only from operations whose results IEEE 754 and OpenCL define exactly: + - * (contraction off, the
 * pragma above), / and sqrt (correctly rounded: build with -cl-fp32-correctly-rounded-divide-sqrt where the
 * device supports it), fabs, copysign, rint, fmin/fmax, comparisons, select, bit casts, integer arithmetic
 * (mul_hi, clz) and int<->float conversions of values that convert exactly. Never fma/mad, transcendental,
 * native_ or half_ builtins.
 *
 * Each algorithm is written once, as a macro over a float type T (float .. float16), its int type I and
 * uint type U, with select() instead of branches that could differ per lane, so every lane of a vector
 * call does exactly the operations of the scalar call: the vector width never changes a result. The only
 * branches (the Payne-Hanek reduction, erf's tail) are taken when any lane needs them and their results
 * are selected per lane. Masks come from comparisons (1 for scalars, -1 for vectors: select() takes both,
 * and & | ^ ! keep both conventions; never ~ on a mask).
 *
 * Denormals: no result depends on whether a device flushes them. Denormal inputs are read as zeros of
 * their sign (decided on the bits, so a device that flushes reads the same); intermediates of normal
 * inputs stay normal wherever they could change a result (where a denormal could appear, it is below half
 * an ulp of what it is added to, which rounds the same whether it is kept or flushed); results below
 * FLT_MIN are returned as zeros of their sign (a quotient or product near FLT_MIN is decided before it can
 * round into, or be flushed from, the denormal range). NaN results are the quiet NaN 0x7fc00000,
 * whatever the input's payload.
 *
 * Error bounds are in ulp of the correctly rounded result, over the whole input range, as measured by
 * tests/exact_math_test.cpp and exhaustively over all floats for the one-argument functions. */
#ifndef PATHCL_EXACT_MATH_CL
#define PATHCL_EXACT_MATH_CL

#define PC_OVL __attribute__((overloadable))
#define PC_NAN_BITS 0x7fc00000u

/* pi/2, pi and 1/ln 2 as the sum of two floats (hi + lo). */
#define PC_PIO2_HI 0x1.921fb6p+0f
#define PC_PIO2_LO -0x1.777a5cp-25f
#define PC_PI_HI 0x1.921fb6p+1f
#define PC_PI_LO -0x1.777a5cp-24f
#define PC_INV_LN2_HI 0x1.715476p+0f
#define PC_INV_LN2_LO 0x1.4ae0cp-26f

/* Bit casts and conversions under one name per type, for the algorithm macros below. */
#define PC_EM_TYPE(T, I, U, N)                                                       \
  inline PC_OVL U pc_bits_(T x) { return as_uint##N(x); }                            \
  inline PC_OVL T pc_float_(U b) { return as_float##N(b); }                          \
  inline PC_OVL I pc_int_(U b) { return as_int##N(b); }                              \
  inline PC_OVL U pc_uint_(I i) { return as_uint##N(i); }                            \
  inline PC_OVL T pc_to_float_(I i) { return convert_float##N(i); }                  \
  inline PC_OVL T pc_to_float_(U i) { return convert_float##N(i); }                  \
  inline PC_OVL I pc_to_int_(T x) { return convert_int##N(x); }                      \
  /* x, and a denormal x as a zero of its sign. */                                   \
  inline PC_OVL T pc_flush_(T x) { return select(x, copysign((T)0.0f, x), fabs(x) < FLT_MIN); } \
  /* A product p of normal numbers, as a zero where it is at most FLT_MIN: a product rounded up to FLT_MIN \
   * by gradual underflow may be flushed on a device that detects tininess before rounding. */ \
  inline PC_OVL T pc_flush_product_(T p) { return select(p, copysign((T)0.0f, p), fabs(p) <= FLT_MIN); }

inline PC_OVL int pc_any_(int m) { return m != 0; }
#define PC_EM_ANY(I) \
  inline PC_OVL int pc_any_(I m) { return any(m); }

/* Error-free transformations (round to nearest, no FMA, no overflow; callers keep the operands where the
 * low parts stay normal or below half an ulp of what they are added to):
 *   two_sum: s + e = a + b exactly (Knuth);  fast_two_sum: the same when exponent(a) >= exponent(b);
 *   two_prod: p + e = a * b exactly (Dekker, with Veltkamp's split into 12-bit halves). */
#define PC_EM_DOUBLE_FLOAT(T)                                                        \
  inline PC_OVL T pc_two_sum_(T a, T b, T* e) {                                      \
    T s = a + b, bb = s - a;                                                         \
    *e = (a - (s - bb)) + (b - bb);                                                  \
    return s;                                                                        \
  }                                                                                  \
  inline PC_OVL T pc_fast_two_sum_(T a, T b, T* e) {                                 \
    T s = a + b;                                                                     \
    *e = b - (s - a);                                                                \
    return s;                                                                        \
  }                                                                                  \
  inline PC_OVL T pc_split_(T a, T* lo) {                                            \
    T c = 4097.0f * a, hi = c - (c - a);                                             \
    *lo = a - hi;                                                                    \
    return hi;                                                                       \
  }                                                                                  \
  inline PC_OVL T pc_two_prod_(T a, T b, T* e) {                                     \
    T p = a * b, al, bl, ah = pc_split_(a, &al), bh = pc_split_(b, &bl);             \
    *e = ((ah * bh - p) + ah * bl + al * bh) + al * bl;                              \
    return p;                                                                        \
  }

/* ---- sin, cos ------------------------------------------------------------------------------------------
 * pc_sin, pc_cos: error <= 1 ulp for all finite x (0.92, 0.93 over all floats); sin(+-0) = +-0,
 * cos(+-0) = 1, NaN and +-inf give NaN. pc_sincos(x, &c) returns sin x and stores cos x (one reduction).
 * x = k pi/2 + r, |r| <= pi/4, with r as hi + lo (about 48 bits; the smallest |r| of any float is about 2^-29):
 * Cody-Waite for |x| < 4096, Payne-Hanek (integer, exact) above. */

/* pi/2 in pieces: four of at most 12 bits (k * piece is exact for k < 4096), the last one 24 bits. */
#define PC_CW1 0x1.922p+0f
#define PC_CW2 -0x1.28p-18f
#define PC_CW3 -0x1.778p-25f
#define PC_CW4 0x1.69p-39f
#define PC_CW5 -0x1.ee59dap-50f

#define PC_EM_SINCOS(T, I, U)                                                                             \
  /* 0 <= a < 4096 (k <= 2608): the first two subtractions are exact (Sterbenz, then both terms are       \
   * multiples of 2^-24 below 1), the next two error-free, the last product's error below 2^-60. */      \
  inline PC_OVL T pc_reduce_cody_waite_(T a, T* lo, I* q) {                                               \
    T k = rint(a * 0x1.45f306p-1f), e1, e2;                                                               \
    T t = (a - k * PC_CW1) - k * PC_CW2;                                                                  \
    T h = pc_two_sum_(t, -(k * PC_CW3), &e1);                                                             \
    h = pc_two_sum_(h, -(k * PC_CW4), &e2);                                                               \
    *q = pc_to_int_(k);                                                                                   \
    return pc_fast_two_sum_(h, (e1 + e2) - k * PC_CW5, lo);                                               \
  }                                                                                                       \
  /* Word i (0..7) of 2/pi's bits behind one zero word (padding for exponents below the binary point). */ \
  inline PC_OVL U pc_two_over_pi_word_(U i) {                                                             \
    I b0 = (i & 1u) != 0u, b1 = (i & 2u) != 0u, b2 = (i & 4u) != 0u;                                      \
    U w01 = select((U)0u, (U)0xa2f9836eu, b0), w23 = select((U)0x4e441529u, (U)0xfc2757d1u, b0);          \
    U w45 = select((U)0xf534ddc0u, (U)0xdb629599u, b0), w67 = select((U)0x3c439041u, (U)0xfe5163abu, b0); \
    return select(select(w01, w23, b1), select(w45, w67, b1), b2);                                        \
  }                                                                                                       \
  /* 4096 <= a < inf, a = m 2^E: x 2/pi mod 4 = m W 2^-94 mod 4 for the 96-bit window W of 2/pi that      \
   * starts at bit E - 1 (earlier bits give multiples of 4, later ones less than 2^-70). */               \
  inline PC_OVL T pc_reduce_payne_hanek_(T a, T* lo, I* q) {                                              \
    U b = pc_bits_(a), m = (b & 0x7fffffu) | 0x800000u;                                                   \
    U start = (b >> 23) - 120u, w = start >> 5, s = start & 31u;                                          \
    U a0 = pc_two_over_pi_word_(w), a1 = pc_two_over_pi_word_(w + 1u);                                    \
    U a2 = pc_two_over_pi_word_(w + 2u), a3 = pc_two_over_pi_word_(w + 3u);                               \
    /* mul_hi(x, 2^s) is x >> (32 - s), 0 for s = 0 (a shift by 32 would count modulo 32). Written so,   \
     * rather than as a shift pair, also because LLVM turns shift pairs into a funnel-shift intrinsic     \
     * that Oclgrind cannot execute. */                                                                   \
    U ps = (U)1u << s, w0 = (a0 << s) | mul_hi(a1, ps), w1 = (a1 << s) | mul_hi(a2, ps);                     \
    U w2 = (a2 << s) | mul_hi(a3, ps);                                                                    \
    /* f = m W mod 2^96: the top two bits are the quadrant, the other 94 the fraction. */                 \
    U f2 = m * w2, c2 = mul_hi(m, w2), f1 = m * w1 + c2;                                                  \
    U f0 = m * w0 + mul_hi(m, w1) + select((U)0u, (U)1u, f1 < c2);                                        \
    U g0 = (f0 << 2) | mul_hi(f1, (U)4u), g1 = (f1 << 2) | mul_hi(f2, (U)4u), g2 = f2 << 2;                     \
    /* Round to the nearest quadrant: a fraction >= 1/2 is the negative fraction - 1 in two's complement. */ \
    I neg = (g0 >> 31) != 0u;                                                                             \
    *q = pc_int_((f0 >> 30) + (g0 >> 31));                                                                \
    U n2 = ~g2 + 1u, n1 = ~g1 + select((U)0u, (U)1u, n2 == 0u);                                           \
    U n0 = ~g0 + select((U)0u, (U)1u, (n2 == 0u) & (n1 == 0u));                                           \
    g0 = select(g0, n0, neg);                                                                             \
    g1 = select(g1, n1, neg);                                                                             \
    g2 = select(g2, n2, neg);                                                                             \
    /* |fraction| >= 2^-29.9 for every float >= 4096 (found exhaustively), so g0 != 0: normalise it and   \
     * take 48 bits as hi + lo, both exact, then multiply by pi/2 in double-float. */                     \
    U lz = clz(g0);                                                                                       \
    U pz = (U)1u << lz, h0 = (g0 << lz) | mul_hi(g1, pz), h1 = (g1 << lz) | mul_hi(g2, pz);                  \
    T fh = pc_to_float_(h0 >> 8) * pc_float_((103u - lz) << 23);                                          \
    T fl = pc_to_float_(((h0 & 0xffu) << 16) | mul_hi(h1, (U)0x10000u)) * pc_float_((79u - lz) << 23);       \
    T e, p = pc_two_prod_(fh, PC_PIO2_HI, &e);                                                            \
    T hi = pc_fast_two_sum_(p, e + (fh * PC_PIO2_LO + fl * PC_PIO2_HI), lo);                              \
    *lo = select(*lo, -*lo, neg);                                                                         \
    return select(hi, -hi, neg);                                                                          \
  }                                                                                                       \
  inline PC_OVL T pc_sincos(T x, T* cosval) {                                                             \
    U b = pc_bits_(x), ab = b & 0x7fffffffu;                                                              \
    T a = pc_float_(select(ab, (U)0u, ab < 0x00800000u)), lo;                                             \
    I q, big = (ab >= 0x45800000u) & (ab < 0x7f800000u); /* 4096 <= |x| < inf */                          \
    T hi = pc_reduce_cody_waite_(fmin(a, 4096.0f), &lo, &q);                                              \
    if (pc_any_(big)) {                                                                                   \
      T lo_big;                                                                                           \
      I q_big;                                                                                            \
      T hi_big = pc_reduce_payne_hanek_(select((T)4096.0f, a, big), &lo_big, &q_big);                     \
      hi = select(hi, hi_big, big);                                                                       \
      lo = select(lo, lo_big, big);                                                                       \
      q = select(q, q_big, big);                                                                          \
    }                                                                                                     \
    /* Minimax polynomials on |r| <= pi/4 + 0.001 (relative errors 2^-28, 2^-33); lo enters to first     \
     * order; cos recovers the rounding error of 1 - z/2. */                                              \
    T z = hi * hi;                                                                                        \
    T s = hi + (hi * (z * (-0x1.555546p-3f + z * (0x1.11077ap-7f + z * -0x1.99548cp-13f))) + lo);         \
    T hz = 0.5f * z, w = 1.0f - hz;                                                                       \
    T c = w + (((1.0f - w) - hz) + (z * z * (0x1.55554ap-5f + z * (-0x1.6c0c28p-10f + z * 0x1.99e80cp-16f)) - hi * lo)); \
    I odd = (q & 1) != 0, bad = ab >= 0x7f800000u;                                                        \
    T sv = pc_float_(pc_bits_(select(s, c, odd)) ^ (pc_uint_(q & 2) << 30) ^ (b & 0x80000000u));          \
    T cv = pc_float_(pc_bits_(select(c, s, odd)) ^ (pc_uint_((q + 1) & 2) << 30));                        \
    *cosval = select(cv, pc_float_((U)PC_NAN_BITS), bad);                                                 \
    return select(sv, pc_float_((U)PC_NAN_BITS), bad);                                                   \
  }                                                                                                       \
  inline PC_OVL T pc_sin(T x) {                                                                           \
    T c;                                                                                                  \
    return pc_sincos(x, &c);                                                                              \
  }                                                                                                       \
  inline PC_OVL T pc_cos(T x) {                                                                           \
    T c;                                                                                                  \
    pc_sincos(x, &c);                                                                                     \
    return c;                                                                                             \
  }

/* ---- atan2 ---------------------------------------------------------------------------------------------
 * pc_atan2(y, x): error <= 2 ulp (1.5 measured on 10^7 pairs). C99/IEEE special cases: atan2(+-0, +0) = +-0, atan2(+-0, -0) = +-pi,
 * atan2(+-0, x < 0) = +-pi, atan2(+-y, +-0) = +-pi/2 (y > 0), atan2(+-y, +inf) = +-0, atan2(+-y, -inf) =
 * +-pi (finite y > 0), atan2(+-inf, x) = +-pi/2 (finite x), atan2(+-inf, +inf) = +-pi/4, atan2(+-inf, -inf)
 * = +-3pi/4, NaN in either -> NaN. Results below FLT_MIN (|y| tiny against x > 0) are +-0.
 * t = min / max of |y|, |x| in [0, 1], atan t by one minimax polynomial (relative error 2^-28.5), placed
 * as off + -atan t with off in {0, pi/2, pi} (a double-float sum). */
#define PC_EM_ATAN2(T, I, U)                                                                              \
  inline PC_OVL T pc_atan2(T y, T x) {                                                                    \
    U yb = pc_bits_(y), xb = pc_bits_(x), ya = yb & 0x7fffffffu, xa = xb & 0x7fffffffu;                   \
    T a = pc_float_(select(ya, (U)0u, ya < 0x00800000u)), b = pc_float_(select(xa, (U)0u, xa < 0x00800000u)); \
    T num = fmin(a, b), den = fmax(a, b);                                                                 \
    /* The quotient is taken 2^32 times larger where den allows it, so one below FLT_MIN is known         \
     * before it could be rounded to a denormal or flushed (below 2^-94 den, it cannot be that small). */ \
    I scaled = den >= 0x1p-94f;                                                                           \
    T qv = num / select(den, den * 0x1p-32f, scaled);                                                     \
    T t = select(qv, qv * 0x1p-32f, scaled);                                                              \
    t = select(t, (T)0.0f, (scaled & (qv < 0x1p-94f)) | (den == 0.0f));                                   \
    t = select(t, (T)1.0f, num == INFINITY);                                                              \
    T z = t * t;                                                                                          \
    T p = t * (z * (-0x1.55553ep-2f + z * (0x1.9991eap-3f + z * (-0x1.2420fap-3f + z * (0x1.c092dcp-4f +  \
          z * (-0x1.5820e6p-4f + z * (0x1.da89bcp-5f + z * (-0x1.fe56ap-6f + z * (0x1.652706p-7f +        \
          z * -0x1.d552cap-10f)))))))));                                                                  \
    /* |y| = |x| (infinities included): atan 1 = pi/4 as hi + lo, so that +-pi/4 and +-3pi/4 are exact. */ \
    I diagonal = t == 1.0f;                                                                               \
    t = select(t, (T)0x1.921fb6p-1f, diagonal);                                                           \
    p = select(p, (T)-0x1.777a5cp-26f, diagonal);                                                         \
    /* atan2 = off +- (t + p): off = 0 (+), pi/2 when |y| > |x| (-, or + for x < 0), pi for x < 0 (-). */ \
    I swap = a > b, xneg = (xb >> 31) != 0u, flip = swap ^ xneg;                                          \
    T off_hi = select(select((T)0.0f, (T)PC_PI_HI, xneg), (T)PC_PIO2_HI, swap);                           \
    T off_lo = select(select((T)0.0f, (T)PC_PI_LO, xneg), (T)PC_PIO2_LO, swap);                           \
    T e, h = pc_two_sum_(off_hi, select(t, -t, flip), &e);                                                \
    T r = h + (e + (off_lo + select(p, -p, flip)));                                                       \
    r = pc_float_(pc_bits_(r) ^ (yb & 0x80000000u));                                                      \
    return select(r, pc_float_((U)PC_NAN_BITS), (xa > 0x7f800000u) | (ya > 0x7f800000u));                \
  }

/* ---- acos ----------------------------------------------------------------------------------------------
 * pc_acos(x): error <= 1 ulp on [-1, 1] (0.89 over all floats); acos(1) = +0, acos(-1) = pi (rounded), |x| > 1 and NaN -> NaN.
 * asin s = s + s z B(z) (z = s^2 <= 1/4, relative error 2^-31.7) for s = |x| < 1/2, else for
 * s = sqrt((1 - |x|) / 2), whose rounding error c is recovered for x > 0 (Sun's fdlibm scheme). */
#define PC_EM_ACOS(T, I, U)                                                                               \
  inline PC_OVL T pc_acos(T x) {                                                                          \
    U b = pc_bits_(x), ab = b & 0x7fffffffu;                                                              \
    I tiny = ab < 0x00800000u, small = ab < 0x3f000000u; /* |x| < 1/2 */                                  \
    T xs = pc_float_(select(b, b & 0x80000000u, tiny)), ax = fabs(xs);                                    \
    T zb = (1.0f - ax) * 0.5f, s = sqrt(zb); /* exact, then >= 2^-25 or 0 */                              \
    T z = select(zb, xs * xs, small);                                                                     \
    T p = z * (0x1.55554cp-3f + z * (0x1.3338a4p-4f + z * (0x1.6ca968p-5f + z * (0x1.04bbd2p-5f +         \
          z * (0x1.d6c57cp-7f + z * 0x1.341eb4p-5f)))));                                                  \
    T r_small = PC_PIO2_HI - (xs - (PC_PIO2_LO - xs * p));                                                \
    T df = pc_float_(pc_bits_(s) & 0xfffff000u); /* s to 12 bits: df * df is exact */                     \
    T c = (zb - df * df) / select(s + df, (T)1.0f, s == 0.0f);                                            \
    T r_pos = 2.0f * (df + (s * p + c));                                                                  \
    T r_neg = 2.0f * (PC_PIO2_HI - (s + (s * p - PC_PIO2_LO)));                                           \
    T r = select(select(r_pos, r_neg, (b >> 31) != 0u), r_small, small);                                  \
    return select(r, pc_float_((U)PC_NAN_BITS), ab > 0x3f800000u);                                        \
  }

/* ---- log, exp2, exp, powr -------------------------------------------------------------------------------
 * pc_log(x): natural log, error <= 1 ulp (0.84 over all floats); log(+-0) = -inf (denormals too), log(x < 0) = NaN, log(+inf) =
 * +inf, NaN -> NaN. x = 2^k (1 + f), sqrt(1/2) <= 1 + f < sqrt(2), s = f / (2 + f):
 * log(1 + f) = f - f^2/2 + s (f^2/2 + z L(z)), z = s^2 <= 0.0295 (L: relative error 2^-35 of the whole). */
#define PC_EM_LOG(T, I, U)                                                                                \
  inline PC_OVL T pc_log_poly_(T z) {                                                                     \
    return z * (0x1.555554p-1f + z * (0x1.999c26p-2f + z * (0x1.23d3dap-2f + z * 0x1.f13d2p-3f)));         \
  }                                                                                                       \
  /* For x positive and normal: 1 + f in [sqrt(1/2), sqrt(2)) and k. */                                   \
  inline PC_OVL T pc_log_reduce_(T x, T* k) {                                                             \
    U iy = pc_bits_(x) + (0x3f800000u - 0x3f3504f3u);                                                     \
    *k = pc_to_float_(pc_int_(iy >> 23) - 127);                                                           \
    return pc_float_((iy & 0x7fffffu) + 0x3f3504f3u);                                                     \
  }                                                                                                       \
  inline PC_OVL T pc_log(T x) {                                                                           \
    U b = pc_bits_(x);                                                                                    \
    I normal = (b >= 0x00800000u) & (b < 0x7f800000u);                                                    \
    T k, f = pc_log_reduce_(select((T)1.0f, x, normal), &k) - 1.0f; /* exact */                           \
    T s = f / (2.0f + f), hfsq = 0.5f * f * f;                                                            \
    /* k ln2_hi is exact: ln2_hi has 16 bits, |k| <= 126 */                                               \
    T r = s * (hfsq + pc_log_poly_(s * s)) + k * 0x1.7f7d1cp-20f - hfsq + f + k * 0x1.62e4p-1f;           \
    r = select(r, (T)(-INFINITY), (b & 0x7fffffffu) < 0x00800000u);                                       \
    r = select(r, (T)INFINITY, b == 0x7f800000u);                                                         \
    return select(r, pc_float_((U)PC_NAN_BITS), (b > 0x7f800000u) & ((b & 0x7fffffffu) >= 0x00800000u));  \
  }                                                                                                       \
  /* 2^(th + tl) for |tl| <= 2^-20 |th| or so; |th| > 200 saturates (to 0 or inf); results below FLT_MIN  \
   * are +0: the exponent is added in the bits, never by a multiplication that could round. 2^r - 1 on   \
   * |r| <= 1/2 by a minimax polynomial (relative error 2^-28.3). */                                      \
  inline PC_OVL T pc_exp2_dd_(T th, T tl) {                                                               \
    tl = select(tl, (T)0.0f, fabs(th) > 200.0f);                                                          \
    th = fmin(fmax(th, -200.0f), 200.0f);                                                                 \
    T n = rint(th), r = (th - n) + tl;                                                                    \
    T p = 1.0f + r * (0x1.62e43p-1f + r * (0x1.ebfbdcp-3f + r * (0x1.c6af7ap-5f + r * (0x1.3b2dd6p-7f +   \
          r * (0x1.5f095cp-10f + r * 0x1.4176a4p-13f)))));                                                \
    I ni = pc_to_int_(n), e = pc_int_(pc_bits_(p) >> 23) + ni; /* the result's biased exponent */         \
    T res = pc_float_(pc_bits_(p) + (pc_uint_(ni) << 23));                                                \
    res = select(res, (T)0.0f, e <= 0);                                                                   \
    return select(res, (T)INFINITY, e >= 255);                                                            \
  }                                                                                                       \
  /* e^x for finite x, through x log2(e) in double-float. */                                              \
  inline PC_OVL T pc_exp_finite_(T x) {                                                                   \
    x = fmin(fmax(x, -104.0f), 90.0f);                                                                    \
    T tl, th = pc_two_prod_(x, PC_INV_LN2_HI, &tl);                                                       \
    return pc_exp2_dd_(th, tl + x * PC_INV_LN2_LO);                                                       \
  }                                                                                                       \
  /* pc_exp2(x), pc_exp(x): error <= 1.5 ulp (1.08, 1.17 over all floats); +inf -> +inf, -inf -> +0,    \
   * results below FLT_MIN -> +0. */                                                                      \
  inline PC_OVL T pc_exp2(T x) {                                                                          \
    U b = pc_bits_(x), ab = b & 0x7fffffffu;                                                              \
    T r = pc_exp2_dd_(pc_float_(select(b, b & 0x80000000u, ab < 0x00800000u)), (T)0.0f);                  \
    return select(r, pc_float_((U)PC_NAN_BITS), ab > 0x7f800000u);                                        \
  }                                                                                                       \
  inline PC_OVL T pc_exp(T x) {                                                                           \
    U b = pc_bits_(x), ab = b & 0x7fffffffu;                                                              \
    T r = pc_exp_finite_(pc_float_(select(b, b & 0x80000000u, ab < 0x00800000u)));                        \
    return select(r, pc_float_((U)PC_NAN_BITS), ab > 0x7f800000u);                                        \
  }                                                                                                       \
  /* log2 x as hi + lo for x positive and normal (relative error about 2^-32): x = 2^k m, m = c (1 + s) /  \
   * (1 - s) with c = 2^(-1/3), 1 or 2^(1/3) (as floats) nearest to m, so |s| <= 0.058; s = (m - c) /     \
   * (m + c) in double-float (m - c is exact), log(m / c) = 2 atanh s = 2s + s z L(z). */                 \
  inline PC_OVL T pc_log2_dd_(T x, T* lo) {                                                               \
    T k, m = pc_log_reduce_(x, &k);                                                                       \
    I below = m < 0x1.c823ep-1f, above = m >= 0x1.1f59acp+0f; /* 2^(-1/6), 2^(1/6) */                    \
    T c = select(select((T)1.0f, (T)0x1.428a3p+0f, above), (T)0x1.965feap-1f, below);                     \
    T c_hi = select(select((T)0.0f, (T)0x1.555558p-2f, above), (T)-0x1.555556p-2f, below);                \
    T c_lo = select(select((T)0.0f, (T)-0x1.a45606p-27f, above), (T)-0x1.0c3d7ep-27f, below);             \
    T f = m - c, dl, dh = pc_two_sum_(m, c, &dl);                                                         \
    T sh = f / dh, pe, p = pc_two_prod_(sh, dh, &pe);                                                     \
    T sl = (((f - p) - pe) - sh * dl) / dh;                                                               \
    T a = 2.0f * sh, bb = 2.0f * sl + sh * pc_log_poly_(sh * sh); /* log(m / c) = a + bb */               \
    T he, h = pc_two_prod_(a, PC_INV_LN2_HI, &he);                                                        \
    T e1, e2, u = pc_two_sum_(k, c_hi, &e1), hi = pc_two_sum_(u, h, &e2);                                 \
    return pc_fast_two_sum_(hi, e2 + (e1 + (c_lo + (he + (a * PC_INV_LN2_LO + bb * PC_INV_LN2_HI)))), lo); \
  }                                                                                                       \
  /* pc_powr(x, y) = x^y for x >= 0 (OpenCL powr): error <= 2 ulp (1.2 measured on 10^7 pairs, Phong's    \
   * cos^n with n <= 10^4 and |y log2 x| near 126 among them), as 2^(y log2 x) with log2 x and its        \
   * product with y in double-float. Special cases as OpenCL's powr: x < 0 -> NaN; powr(x, +-0) = 1 for  \
   * finite x > 0; powr(+-0, y) = +inf for y < 0 (-inf included), +0 for y > 0; powr(+-0, +-0) = NaN;     \
   * powr(+inf, +-0) = NaN; powr(+1, y) = 1 for finite y; powr(+1, +-inf) = NaN; NaN -> NaN; otherwise   \
   * the limits (powr(x < 1, +inf) = +0, powr(+inf, y > 0) = +inf, ...). Results below FLT_MIN -> +0. */ \
  inline PC_OVL T pc_powr(T x, T y) {                                                                     \
    U xb = pc_bits_(x), yb = pc_bits_(y), ya = yb & 0x7fffffffu;                                          \
    xb = select(xb, xb & 0x80000000u, (xb & 0x7fffffffu) < 0x00800000u);                                  \
    yb = select(yb, yb & 0x80000000u, ya < 0x00800000u);                                                  \
    x = pc_float_(xb);                                                                                    \
    y = pc_float_(yb);                                                                                    \
    I normal = (xb >= 0x00800000u) & (xb < 0x7f800000u); /* x positive, normal */                         \
    T lo, hi = pc_log2_dd_(select((T)1.0f, x, normal), &lo);                                              \
    /* |y| <= 2^64 keeps the split exact; beyond it |y log2 x| > 200 (or log2 x = 0) anyway. */           \
    T yc = fmin(fmax(y, -0x1p64f), 0x1p64f), tl, th = pc_two_prod_(yc, hi, &tl);                          \
    T r = pc_exp2_dd_(th, tl + yc * lo);                                                                  \
    I yzero = y == 0.0f, ypos = (yb >> 31) == 0u;                                                         \
    r = select(r, select(select((T)INFINITY, (T)0.0f, ypos), pc_float_((U)PC_NAN_BITS), yzero), x == 0.0f); \
    r = select(r, select(select((T)0.0f, (T)INFINITY, ypos), pc_float_((U)PC_NAN_BITS), yzero), xb == 0x7f800000u); \
    I nan = (xb > 0x80000000u) | ((xb > 0x7f800000u) & (xb < 0x80000000u)) | (ya > 0x7f800000u) |        \
            ((xb == 0x3f800000u) & (ya == 0x7f800000u));                                                  \
    return select(r, pc_float_((U)PC_NAN_BITS), nan);                                                     \
  }

/* ---- erf -----------------------------------------------------------------------------------------------
 * pc_erf(x): error <= 2 ulp (1.31 over all floats); erf(+-0) = +-0, erf(+-inf) = +-1, NaN -> NaN.
 * |x| < 1: x + x P(x^2) (relative error 2^-29.4); 1 <= |x| < 4: 1 - e^(G(|x| - 2.5) - x^2) with
 * G = log(erfc(x) e^(x^2)) (error 2^-29.8 in erf); |x| >= 4: 1 (erfc(4) < 2^-25). */
#define PC_EM_ERF(T, I, U)                                                                                \
  inline PC_OVL T pc_erf(T x) {                                                                           \
    U b = pc_bits_(x), ab = b & 0x7fffffffu;                                                              \
    T ax = pc_float_(select(ab, (U)0u, ab < 0x00800000u));                                                \
    /* Tiny x: x P(x^2), about x/8, is computed 2^64 times larger so that it is never denormal. */       \
    I tiny = ax < 0x1p-64f;                                                                               \
    T as = ax * select((T)1.0f, (T)0x1p64f, tiny), z = ax * ax;                                           \
    T r = as + as * (0x1.06eba8p-3f + z * (-0x1.81273ep-2f + z * (0x1.ce2ce6p-4f + z * (-0x1.b7f71ap-6f + \
          z * (0x1.53f226p-8f + z * (-0x1.a35186p-11f + z * 0x1.4772cp-14f))))));                         \
    r = r * select((T)1.0f, (T)0x1p-64f, tiny);                                                           \
    I tail = ax >= 1.0f;                                                                                  \
    if (pc_any_(tail)) {                                                                                  \
      T at = fmin(ax, 4.0f), u = fmax(at, 1.0f) - 2.5f; /* exact */                                       \
      T g = -0x1.8e8b9cp+0f + u * (-0x1.69289p-2f + u * (0x1.cbb1a8p-5f + u * (-0x1.5f2ff2p-7f +          \
            u * (0x1.422ce8p-9f + u * (-0x1.470526p-13f + u * 0x1.85313ep-13f)))));                       \
      r = select(r, 1.0f - pc_exp_finite_(g - at * at), tail);                                            \
      r = select(r, (T)1.0f, ax >= 4.0f);                                                                 \
    }                                                                                                     \
    r = pc_float_(pc_bits_(r) | (b & 0x80000000u));                                                       \
    return select(r, pc_float_((U)PC_NAN_BITS), ab > 0x7f800000u);                                        \
  }

#define PC_EM_ALL(T, I, U, N) \
  PC_EM_TYPE(T, I, U, N)      \
  PC_EM_DOUBLE_FLOAT(T)       \
  PC_EM_SINCOS(T, I, U)       \
  PC_EM_ATAN2(T, I, U)        \
  PC_EM_ACOS(T, I, U)         \
  PC_EM_LOG(T, I, U)          \
  PC_EM_ERF(T, I, U)
PC_EM_ANY(int2)
PC_EM_ANY(int3)
#if defined(__clang__) && defined(__AVX512DQ__) && defined(__AVX512VL__)
/* x86 CPUs with AVX-512 (PoCL, Intel's CPU runtime): a mask of 4, 8 or 16 lanes (-1 or 0 each) as its sign
 * bits, which the compiler takes straight from the comparison's mask register (one kmov); also
 * kernels/lanes.cl's pc_lane_bits. */
#define PC_AVX512_MASKS 1
inline PC_OVL uint pc_sign_bits_(int4 m) { return (uint)__builtin_ia32_cvtd2mask128(m); }
inline PC_OVL uint pc_sign_bits_(int8 m) { return (uint)__builtin_ia32_cvtd2mask256(m); }
inline PC_OVL uint pc_sign_bits_(int16 m) { return (uint)__builtin_ia32_cvtd2mask512(m); }
inline PC_OVL int pc_any_(int4 m) { return pc_sign_bits_(m) != 0u; }
inline PC_OVL int pc_any_(int8 m) { return pc_sign_bits_(m) != 0u; }
inline PC_OVL int pc_any_(int16 m) { return pc_sign_bits_(m) != 0u; }
#else
/* Masks of 4, 8 and 16 lanes (-1 or 0 each) narrowed to bytes and read as one or two integers: a few vector
 * instructions, where PoCL's any() is a loop over the lanes (it took a tenth of the 16-lane path kernel's
 * time). */
inline PC_OVL int pc_any_(int4 m) { return as_uint(convert_char4(m)) != 0u; }
inline PC_OVL int pc_any_(int8 m) { return as_ulong(convert_char8(m)) != 0ul; }
inline PC_OVL int pc_any_(int16 m) {
  ulong2 b = as_ulong2(convert_char16(m));
  return (b.x | b.y) != 0ul;
}
#endif
PC_EM_ALL(float, int, uint, )
PC_EM_ALL(float2, int2, uint2, 2)
PC_EM_ALL(float3, int3, uint3, 3)
PC_EM_ALL(float4, int4, uint4, 4)
PC_EM_ALL(float8, int8, uint8, 8)
PC_EM_ALL(float16, int16, uint16, 16)

/* ---- dot, cross, length, normalize ----------------------------------------------------------------------
 * pc_dot (float2/3/4): the products, then their sum from left to right, each rounded once (not fused), so
 * the result is the one of that written-out sum: no error bound beyond the rounding of each operation.
 * pc_cross (float3; float4 with w = 0): a.y b.z - a.z b.y, ... the same way.
 * Denormal inputs are zeros, products at most FLT_MIN and sums below it are zeros of their sign, so a
 * device that flushes denormals gets the same bits. */
inline PC_OVL float pc_dot(float2 a, float2 b) {
  float2 p = pc_flush_product_(pc_flush_(a) * pc_flush_(b));
  return pc_flush_(p.x + p.y);
}
inline PC_OVL float pc_dot(float3 a, float3 b) {
  float3 p = pc_flush_product_(pc_flush_(a) * pc_flush_(b));
  return pc_flush_(pc_flush_(p.x + p.y) + p.z);
}
inline PC_OVL float pc_dot(float4 a, float4 b) {
  float4 p = pc_flush_product_(pc_flush_(a) * pc_flush_(b));
  return pc_flush_(pc_flush_(pc_flush_(p.x + p.y) + p.z) + p.w);
}
inline PC_OVL float3 pc_cross(float3 a, float3 b) {
  a = pc_flush_(a);
  b = pc_flush_(b);
  return pc_flush_(pc_flush_product_(a.yzx * b.zxy) - pc_flush_product_(a.zxy * b.yzx));
}
inline PC_OVL float4 pc_cross(float4 a, float4 b) { return (float4)(pc_cross(a.xyz, b.xyz), 0.0f); }

/* pc_length: sqrt of the sum of squares, error <= (n + 2) / 2 ulp for n components (a priori: n roundings
 * in the sum, halved by the square root, plus its own; 1.1 to 1.4 ulp measured); a zero vector has length
 * +0, one with an infinite component +inf, NaN components give NaN.
 * pc_normalize: v / sqrt(v . v), each component's error <= (n + 4) / 2 ulp (the length's and the
 * division's; 2.1 to 2.3 ulp measured); a zero vector is returned as it is (its zeros keep their signs);
 * infinite components become +-1 and the others +-0 before normalising; NaN -> all NaN; components
 * below FLT_MIN -> +-0.
 * The sum of squares is taken as it is when the largest |component| lies in [2^-40, 2^40) (squares of
 * smaller components may be denormal, but are below half an ulp of the largest square, so flushing them
 * cannot change the sum), otherwise after an exact scaling by a power of two that brings it to [2, 4).
 * A component is divided by length 2^-24, so a quotient below FLT_MIN is recognised while it is still
 * normal (2^24 times larger), then scaled back exactly. */
inline PC_OVL uint pc_max_component_(uint2 a) { return max(a.x, a.y); }
inline PC_OVL uint pc_max_component_(uint3 a) { return max(max(a.x, a.y), a.z); }
inline PC_OVL uint pc_max_component_(uint4 a) { return max(max(max(a.x, a.y), a.z), a.w); }
inline PC_OVL float pc_sum_of_squares_(float2 v) { return v.x * v.x + v.y * v.y; }
inline PC_OVL float pc_sum_of_squares_(float3 v) { return v.x * v.x + v.y * v.y + v.z * v.z; }
inline PC_OVL float pc_sum_of_squares_(float4 v) { return v.x * v.x + v.y * v.y + v.z * v.z + v.w * v.w; }

#define PC_EM_GEOMETRIC(V, U, N)                                                                          \
  inline PC_OVL float pc_length(V v) {                                                                    \
    U ab = as_uint##N(v) & 0x7fffffffu;                                                                   \
    ab = select(ab, (U)0u, ab < 0x00800000u);                                                             \
    V va = as_float##N(ab);                                                                               \
    uint mb = pc_max_component_(ab);                                                                      \
    if (mb - 0x2b800000u < 0x28000000u) return sqrt(pc_sum_of_squares_(va)); /* max in [2^-40, 2^40) */   \
    if (mb == 0u) return 0.0f;                                                                            \
    if (mb > 0x7f800000u) return as_float(PC_NAN_BITS);                                                   \
    if (mb == 0x7f800000u) return INFINITY;                                                               \
    float s = as_float((255u - (mb >> 23)) << 23); /* max * s in [2, 4) */                                \
    return sqrt(pc_sum_of_squares_(va * s)) / s;                                                          \
  }                                                                                                       \
  inline PC_OVL V pc_normalize(V v) {                                                                     \
    U b = as_uint##N(v), ab = b & 0x7fffffffu;                                                            \
    ab = select(ab, (U)0u, ab < 0x00800000u);                                                             \
    V v0 = as_float##N(ab | (b & 0x80000000u)), vs = v0;                                                  \
    uint mb = pc_max_component_(ab);                                                                      \
    if (mb - 0x2b800000u >= 0x28000000u) { /* max outside [2^-40, 2^40): zero, inf, NaN or far from 1 */  \
      if (mb == 0u) return v0;                                                                            \
      if (mb > 0x7f800000u) return as_float##N((U)PC_NAN_BITS);                                           \
      if (mb == 0x7f800000u)                                                                              \
        vs = select(copysign((V)0.0f, v0), copysign((V)1.0f, v0), ab == 0x7f800000u);                     \
      else                                                                                                \
        vs = v0 * as_float((255u - (mb >> 23)) << 23);                                                    \
    }                                                                                                     \
    V q = vs / (sqrt(pc_sum_of_squares_(vs)) * 0x1p-24f);                                                 \
    return select(q * 0x1p-24f, copysign((V)0.0f, v0), fabs(q) < 0x1p-102f);                              \
  }
PC_EM_GEOMETRIC(float2, uint2, 2)
PC_EM_GEOMETRIC(float3, uint3, 3)
PC_EM_GEOMETRIC(float4, uint4, 4)


/* ---- The same over lanes: 3-vectors stored by component (x, y, z each a float, float8 or float16 of the
 * lanes' values), for issue 15's lane-generic kernel. Every lane does exactly the operations of the
 * float3 function above (the same products, sums and their order, the same flushes); its branches are
 * selects per lane. So lane j of pc_normalize(lane3f8 v) is pc_normalize of lane j's float3, bit for bit
 * (tests/exact_math_test.cpp, LaneGeometryGivesTheFloat3Bits). */
/* One lane is a float3: its operations are the float3 functions above (on CPU devices one SSE register
 * per vector, on GPUs scalars), with lane3(x, y, z) its constructor. */
typedef float3 lane3f;
inline PC_OVL float3 lane3(float x, float y, float z) { return (float3)(x, y, z); }
typedef struct { float8 x, y, z; } lane3f8;
typedef struct { float16 x, y, z; } lane3f16;

#define PC_EM_LANES3(V3, F, I, U, N)                                                                      \
  inline PC_OVL V3 lane3(F x, F y, F z) {                                                                 \
    V3 v;                                                                                                 \
    v.x = x;                                                                                              \
    v.y = y;                                                                                              \
    v.z = z;                                                                                              \
    return v;                                                                                             \
  }                                                                                                       \
  inline PC_OVL F pc_dot(V3 a, V3 b) {                                                                    \
    F px = pc_flush_product_(pc_flush_(a.x) * pc_flush_(b.x));                                            \
    F py = pc_flush_product_(pc_flush_(a.y) * pc_flush_(b.y));                                            \
    F pz = pc_flush_product_(pc_flush_(a.z) * pc_flush_(b.z));                                            \
    return pc_flush_(pc_flush_(px + py) + pz);                                                            \
  }                                                                                                       \
  inline PC_OVL V3 pc_cross(V3 a, V3 b) {                                                                 \
    F ax = pc_flush_(a.x), ay = pc_flush_(a.y), az = pc_flush_(a.z);                                      \
    F bx = pc_flush_(b.x), by = pc_flush_(b.y), bz = pc_flush_(b.z);                                      \
    return lane3(pc_flush_(pc_flush_product_(ay * bz) - pc_flush_product_(az * by)),                      \
                 pc_flush_(pc_flush_product_(az * bx) - pc_flush_product_(ax * bz)),                      \
                 pc_flush_(pc_flush_product_(ax * by) - pc_flush_product_(ay * bx)));                     \
  }                                                                                                       \
  /* |component| bits with denormals as zeros, and the largest of them. */                               \
  inline PC_OVL U pc_lane_abs_bits_(F x) {                                                                \
    U a = as_uint##N(x) & 0x7fffffffu;                                                                    \
    return select(a, (U)(0u), a < 0x00800000u);                                                           \
  }                                                                                                       \
  inline PC_OVL F pc_lane_sum_of_squares_(F x, F y, F z) { return x * x + y * y + z * z; }
/* pc_length and pc_normalize of 8 or 16 lanes; those of one lane are the float3 functions, whose early
 * returns are faster than these selects and give the same bits. */
#define PC_EM_LANES3_LENGTH(V3, F, I, U, N)                                                               \
  inline PC_OVL F pc_length(V3 v) {                                                                       \
    U ax = pc_lane_abs_bits_(v.x), ay = pc_lane_abs_bits_(v.y), az = pc_lane_abs_bits_(v.z);              \
    F vx = as_float##N(ax), vy = as_float##N(ay), vz = as_float##N(az);                                   \
    U mb = max(max(ax, ay), az);                                                                          \
    F s = as_float##N((255u - (mb >> 23u)) << 23u); /* max * s in [2, 4) */                               \
    F direct = sqrt(pc_lane_sum_of_squares_(vx, vy, vz));                                                 \
    F scaled = sqrt(pc_lane_sum_of_squares_(vx * s, vy * s, vz * s)) / s;                                 \
    F r = select(scaled, direct, mb - 0x2b800000u < 0x28000000u); /* max in [2^-40, 2^40) */             \
    r = select(r, (F)(0.0f), mb == 0u);                                                                   \
    r = select(r, as_float##N((U)(PC_NAN_BITS)), mb > 0x7f800000u);                                       \
    return select(r, (F)(INFINITY), mb == 0x7f800000u);                                                   \
  }                                                                                                       \
  inline PC_OVL V3 pc_normalize(V3 v) {                                                                   \
    U bx = as_uint##N(v.x), by = as_uint##N(v.y), bz = as_uint##N(v.z);                                   \
    U ax = pc_lane_abs_bits_(v.x), ay = pc_lane_abs_bits_(v.y), az = pc_lane_abs_bits_(v.z);              \
    F v0x = as_float##N(ax | (bx & 0x80000000u)), v0y = as_float##N(ay | (by & 0x80000000u));             \
    F v0z = as_float##N(az | (bz & 0x80000000u));                                                         \
    U mb = max(max(ax, ay), az);                                                                          \
    I zero = mb == 0u, nan = mb > 0x7f800000u, inf = mb == 0x7f800000u;                                   \
    /* max outside [2^-40, 2^40), finite and not zero: scaled by a power of two to [2, 4) */              \
    I far = (mb - 0x2b800000u >= 0x28000000u) & !zero & !nan & !inf;                                      \
    F s = as_float##N((255u - (mb >> 23u)) << 23u);                                                       \
    F sx = select(v0x, v0x * s, far), sy = select(v0y, v0y * s, far), sz = select(v0z, v0z * s, far);     \
    /* infinite components become +-1, the others +-0 */                                                  \
    sx = select(sx, select(copysign((F)(0.0f), v0x), copysign((F)(1.0f), v0x), ax == 0x7f800000u), inf);  \
    sy = select(sy, select(copysign((F)(0.0f), v0y), copysign((F)(1.0f), v0y), ay == 0x7f800000u), inf);  \
    sz = select(sz, select(copysign((F)(0.0f), v0z), copysign((F)(1.0f), v0z), az == 0x7f800000u), inf);  \
    F den = sqrt(pc_lane_sum_of_squares_(sx, sy, sz)) * 0x1p-24f;                                         \
    F qx = sx / den, qy = sy / den, qz = sz / den;                                                        \
    F nan_value = as_float##N((U)(PC_NAN_BITS));                                                          \
    qx = select(qx * 0x1p-24f, copysign((F)(0.0f), v0x), fabs(qx) < 0x1p-102f);                           \
    qy = select(qy * 0x1p-24f, copysign((F)(0.0f), v0y), fabs(qy) < 0x1p-102f);                           \
    qz = select(qz * 0x1p-24f, copysign((F)(0.0f), v0z), fabs(qz) < 0x1p-102f);                           \
    return lane3(select(select(qx, v0x, zero), nan_value, nan), select(select(qy, v0y, zero), nan_value, nan), \
                 select(select(qz, v0z, zero), nan_value, nan));                                          \
  }
PC_EM_LANES3(lane3f8, float8, int8, uint8, 8)
PC_EM_LANES3(lane3f16, float16, int16, uint16, 16)
PC_EM_LANES3_LENGTH(lane3f8, float8, int8, uint8, 8)
PC_EM_LANES3_LENGTH(lane3f16, float16, int16, uint16, 16)
#undef PC_EM_LANES3
#undef PC_EM_LANES3_LENGTH

#endif
