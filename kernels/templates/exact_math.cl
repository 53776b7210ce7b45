/* exact_math.cl's functions of one type: a template, included by exact_math.cl once per width PC_LANE_W
 * (1, 2, 3, 4, 8, 16) with templates/lane_width.h's types F, I and U. */
#include "templates/lane_width.h"

/* Bit casts and conversions under one name per type, for the algorithms below. */
static inline PC_OVL U pc_bits_(F x) { return as_U(x); }
static inline PC_OVL F pc_float_(U b) { return as_F(b); }
static inline PC_OVL I pc_int_(U b) { return as_I(b); }
static inline PC_OVL U pc_uint_(I i) { return as_U(i); }
static inline PC_OVL F pc_to_float_(I i) { return convert_F(i); }
static inline PC_OVL F pc_to_float_(U i) { return convert_F(i); }
static inline PC_OVL I pc_to_int_(F x) { return convert_I(x); }
/* x, and a denormal x as a zero of its sign. Decided on the bits: as floats (fabs, compare, copysign),
 * LLVM took a scalar's sign by vmovmskps and a shift, and these flushes were a ninth of a one-lane BDPT
 * sample (the product flush below measured no faster so written). */
static inline PC_OVL F pc_flush_(F x) {
  U b = as_U(x);
  return as_F(select(b, b & 0x80000000u, (b & 0x7fffffffu) < 0x00800000u));
}
/* A product p of normal numbers, as a zero where it is at most FLT_MIN: a product rounded up to FLT_MIN
 * by gradual underflow may be flushed on a device that detects tininess before rounding. */
static inline PC_OVL F pc_flush_product_(F p) { return select(p, copysign((F)0.0f, p), fabs(p) <= FLT_MIN); }

/* Error-free transformations (round to nearest, no FMA, no overflow; callers keep the operands where the
 * low parts stay normal or below half an ulp of what they are added to):
 *   two_sum: s + e = a + b exactly (Knuth);  fast_two_sum: the same when exponent(a) >= exponent(b);
 *   two_prod: p + e = a * b exactly (Dekker, with Veltkamp's split into 12-bit halves). */
static inline PC_OVL F pc_two_sum_(F a, F b, F* e) {
  F s = a + b, bb = s - a;
  *e = (a - (s - bb)) + (b - bb);
  return s;
}
static inline PC_OVL F pc_fast_two_sum_(F a, F b, F* e) {
  F s = a + b;
  *e = b - (s - a);
  return s;
}
static inline PC_OVL F pc_split_(F a, F* lo) {
  F c = 4097.0f * a, hi = c - (c - a);
  *lo = a - hi;
  return hi;
}
static inline PC_OVL F pc_two_prod_(F a, F b, F* e) {
  F p = a * b, al, bl, ah = pc_split_(a, &al), bh = pc_split_(b, &bl);
  *e = ((ah * bh - p) + ah * bl + al * bh) + al * bl;
  return p;
}

/* ---- sin, cos ------------------------------------------------------------------------------------------
 * pc_sin, pc_cos: error <= 1 ulp for all finite x (0.92, 0.93 over all floats); sin(+-0) = +-0,
 * cos(+-0) = 1, NaN and +-inf give NaN. pc_sincos(x, &c) returns sin x and stores cos x (one reduction).
 * x = k pi/2 + r, |r| <= pi/4, with r as hi + lo (about 48 bits; the smallest |r| of any float is about 2^-29):
 * Cody-Waite for |x| < 4096, Payne-Hanek (integer, exact) above. */

/* 0 <= a < 4096 (k <= 2608): the first two subtractions are exact (Sterbenz, then both terms are
 * multiples of 2^-24 below 1), the next two error-free, the last product's error below 2^-60. */
static inline PC_OVL F pc_reduce_cody_waite_(F a, F* lo, I* q) {
  F k = rint(a * 0x1.45f306p-1f), e1, e2;
  F t = (a - k * PC_CW1) - k * PC_CW2;
  F h = pc_two_sum_(t, -(k * PC_CW3), &e1);
  h = pc_two_sum_(h, -(k * PC_CW4), &e2);
  *q = pc_to_int_(k);
  return pc_fast_two_sum_(h, (e1 + e2) - k * PC_CW5, lo);
}
/* Word i (0..7) of 2/pi's bits behind one zero word (padding for exponents below the binary point). */
static inline PC_OVL U pc_two_over_pi_word_(U i) {
  I b0 = (i & 1u) != 0u, b1 = (i & 2u) != 0u, b2 = (i & 4u) != 0u;
  U w01 = select((U)0u, (U)0xa2f9836eu, b0), w23 = select((U)0x4e441529u, (U)0xfc2757d1u, b0);
  U w45 = select((U)0xf534ddc0u, (U)0xdb629599u, b0), w67 = select((U)0x3c439041u, (U)0xfe5163abu, b0);
  return select(select(w01, w23, b1), select(w45, w67, b1), b2);
}
/* 4096 <= a < inf, a = m 2^E: x 2/pi mod 4 = m W 2^-94 mod 4 for the 96-bit window W of 2/pi that
 * starts at bit E - 1 (earlier bits give multiples of 4, later ones less than 2^-70). */
static inline PC_OVL F pc_reduce_payne_hanek_(F a, F* lo, I* q) {
  U b = pc_bits_(a), m = (b & 0x7fffffu) | 0x800000u;
  U start = (b >> 23) - 120u, w = start >> 5, s = start & 31u;
  U a0 = pc_two_over_pi_word_(w), a1 = pc_two_over_pi_word_(w + 1u);
  U a2 = pc_two_over_pi_word_(w + 2u), a3 = pc_two_over_pi_word_(w + 3u);
  /* mul_hi(x, 2^s) is x >> (32 - s), 0 for s = 0 (a shift by 32 would count modulo 32). Written so,
   * rather than as a shift pair, also because LLVM turns shift pairs into a funnel-shift intrinsic
   * that Oclgrind cannot execute. */
  U ps = (U)1u << s, w0 = (a0 << s) | mul_hi(a1, ps), w1 = (a1 << s) | mul_hi(a2, ps);
  U w2 = (a2 << s) | mul_hi(a3, ps);
  /* f = m W mod 2^96: the top two bits are the quadrant, the other 94 the fraction. */
  U f2 = m * w2, c2 = mul_hi(m, w2), f1 = m * w1 + c2;
  U f0 = m * w0 + mul_hi(m, w1) + select((U)0u, (U)1u, f1 < c2);
  U g0 = (f0 << 2) | mul_hi(f1, (U)4u), g1 = (f1 << 2) | mul_hi(f2, (U)4u), g2 = f2 << 2;
  /* Round to the nearest quadrant: a fraction >= 1/2 is the negative fraction - 1 in two's complement. */
  I neg = (g0 >> 31) != 0u;
  *q = pc_int_((f0 >> 30) + (g0 >> 31));
  U n2 = ~g2 + 1u, n1 = ~g1 + select((U)0u, (U)1u, n2 == 0u);
  U n0 = ~g0 + select((U)0u, (U)1u, (n2 == 0u) & (n1 == 0u));
  g0 = select(g0, n0, neg);
  g1 = select(g1, n1, neg);
  g2 = select(g2, n2, neg);
  /* |fraction| >= 2^-29.9 for every float >= 4096 (found exhaustively), so g0 != 0: normalise it and
   * take 48 bits as hi + lo, both exact, then multiply by pi/2 in double-float. */
  U lz = clz(g0);
  U pz = (U)1u << lz, h0 = (g0 << lz) | mul_hi(g1, pz), h1 = (g1 << lz) | mul_hi(g2, pz);
  F fh = pc_to_float_(h0 >> 8) * pc_float_((103u - lz) << 23);
  F fl = pc_to_float_(((h0 & 0xffu) << 16) | mul_hi(h1, (U)0x10000u)) * pc_float_((79u - lz) << 23);
  F e, p = pc_two_prod_(fh, PC_PIO2_HI, &e);
  F hi = pc_fast_two_sum_(p, e + (fh * PC_PIO2_LO + fl * PC_PIO2_HI), lo);
  *lo = select(*lo, -*lo, neg);
  return select(hi, -hi, neg);
}
/* sin and cos of hi + lo, |hi| <= pi/4 + 0.001 (the reduced argument): minimax polynomials (relative
 * errors 2^-28, 2^-33); lo enters to first order; cos recovers the rounding error of 1 - z/2. */
static inline PC_OVL F pc_sincos_reduced_(F hi, F lo, F* cosval) {
  F z = hi * hi;
  F s = hi + (hi * (z * (-0x1.555546p-3f + z * (0x1.11077ap-7f + z * -0x1.99548cp-13f))) + lo);
  F hz = 0.5f * z, w = 1.0f - hz;
  *cosval = w + (((1.0f - w) - hz) + (z * z * (0x1.55554ap-5f + z * (-0x1.6c0c28p-10f + z * 0x1.99e80cp-16f)) - hi * lo));
  return s;
}
/* sin and cos of x for |x| <= pi/4: pc_sincos's polynomials without its reduction (which leaves such x as
 * it is, up to x = pi/4 itself). */
static inline PC_OVL F pc_sincos_quarter(F x, F* cosval) { return pc_sincos_reduced_(x, (F)(0.0f), cosval); }
static inline PC_OVL F pc_sincos(F x, F* cosval) {
  U b = pc_bits_(x), ab = b & 0x7fffffffu;
  F a = pc_float_(select(ab, (U)0u, ab < 0x00800000u)), lo;
  I q, big = (ab >= 0x45800000u) & (ab < 0x7f800000u); /* 4096 <= |x| < inf */
  F hi = pc_reduce_cody_waite_(fmin(a, 4096.0f), &lo, &q);
  if (pc_any_(big)) {
    F lo_big;
    I q_big;
    F hi_big = pc_reduce_payne_hanek_(select((F)4096.0f, a, big), &lo_big, &q_big);
    hi = select(hi, hi_big, big);
    lo = select(lo, lo_big, big);
    q = select(q, q_big, big);
  }
  F c, s = pc_sincos_reduced_(hi, lo, &c);
  I odd = (q & 1) != 0, bad = ab >= 0x7f800000u;
  F sv = pc_float_(pc_bits_(select(s, c, odd)) ^ (pc_uint_(q & 2) << 30) ^ (b & 0x80000000u));
  F cv = pc_float_(pc_bits_(select(c, s, odd)) ^ (pc_uint_((q + 1) & 2) << 30));
  *cosval = select(cv, pc_float_((U)PC_NAN_BITS), bad);
  return select(sv, pc_float_((U)PC_NAN_BITS), bad);
}
static inline PC_OVL F pc_sin(F x) {
  F c;
  return pc_sincos(x, &c);
}
static inline PC_OVL F pc_cos(F x) {
  F c;
  pc_sincos(x, &c);
  return c;
}

/* ---- atan2 ---------------------------------------------------------------------------------------------
 * pc_atan2(y, x): error <= 2 ulp (1.5 measured on 10^7 pairs). C99/IEEE special cases: atan2(+-0, +0) = +-0, atan2(+-0, -0) = +-pi,
 * atan2(+-0, x < 0) = +-pi, atan2(+-y, +-0) = +-pi/2 (y > 0), atan2(+-y, +inf) = +-0, atan2(+-y, -inf) =
 * +-pi (finite y > 0), atan2(+-inf, x) = +-pi/2 (finite x), atan2(+-inf, +inf) = +-pi/4, atan2(+-inf, -inf)
 * = +-3pi/4, NaN in either -> NaN. Results below FLT_MIN (|y| tiny against x > 0) are +-0.
 * t = min / max of |y|, |x| in [0, 1], atan t by one minimax polynomial (relative error 2^-28.5), placed
 * as off + -atan t with off in {0, pi/2, pi} (a double-float sum). */
static inline PC_OVL F pc_atan2(F y, F x) {
  U yb = pc_bits_(y), xb = pc_bits_(x), ya = yb & 0x7fffffffu, xa = xb & 0x7fffffffu;
  F a = pc_float_(select(ya, (U)0u, ya < 0x00800000u)), b = pc_float_(select(xa, (U)0u, xa < 0x00800000u));
  F num = fmin(a, b), den = fmax(a, b);
  /* The quotient is taken 2^32 times larger where den allows it, so one below FLT_MIN is known
   * before it could be rounded to a denormal or flushed (below 2^-94 den, it cannot be that small). */
  I scaled = den >= 0x1p-94f;
  F qv = num / select(den, den * 0x1p-32f, scaled);
  F t = select(qv, qv * 0x1p-32f, scaled);
  t = select(t, (F)0.0f, (scaled & (qv < 0x1p-94f)) | (den == 0.0f));
  t = select(t, (F)1.0f, num == INFINITY);
  F z = t * t;
  F p = t * (z * (-0x1.55553ep-2f + z * (0x1.9991eap-3f + z * (-0x1.2420fap-3f + z * (0x1.c092dcp-4f +
        z * (-0x1.5820e6p-4f + z * (0x1.da89bcp-5f + z * (-0x1.fe56ap-6f + z * (0x1.652706p-7f +
        z * -0x1.d552cap-10f)))))))));
  /* |y| = |x| (infinities included): atan 1 = pi/4 as hi + lo, so that +-pi/4 and +-3pi/4 are exact. */
  I diagonal = t == 1.0f;
  t = select(t, (F)0x1.921fb6p-1f, diagonal);
  p = select(p, (F)-0x1.777a5cp-26f, diagonal);
  /* atan2 = off +- (t + p): off = 0 (+), pi/2 when |y| > |x| (-, or + for x < 0), pi for x < 0 (-). */
  I swap = a > b, xneg = (xb >> 31) != 0u, flip = swap ^ xneg;
  F off_hi = select(select((F)0.0f, (F)PC_PI_HI, xneg), (F)PC_PIO2_HI, swap);
  F off_lo = select(select((F)0.0f, (F)PC_PI_LO, xneg), (F)PC_PIO2_LO, swap);
  F e, h = pc_two_sum_(off_hi, select(t, -t, flip), &e);
  F r = h + (e + (off_lo + select(p, -p, flip)));
  r = pc_float_(pc_bits_(r) ^ (yb & 0x80000000u));
  return select(r, pc_float_((U)PC_NAN_BITS), (xa > 0x7f800000u) | (ya > 0x7f800000u));
}

/* ---- acos ----------------------------------------------------------------------------------------------
 * pc_acos(x): error <= 1 ulp on [-1, 1] (0.89 over all floats); acos(1) = +0, acos(-1) = pi (rounded), |x| > 1 and NaN -> NaN.
 * asin s = s + s z B(z) (z = s^2 <= 1/4, relative error 2^-31.7) for s = |x| < 1/2, else for
 * s = sqrt((1 - |x|) / 2), whose rounding error c is recovered for x > 0 (Sun's fdlibm scheme). */
static inline PC_OVL F pc_acos(F x) {
  U b = pc_bits_(x), ab = b & 0x7fffffffu;
  I tiny = ab < 0x00800000u, small = ab < 0x3f000000u; /* |x| < 1/2 */
  F xs = pc_float_(select(b, b & 0x80000000u, tiny)), ax = fabs(xs);
  F zb = (1.0f - ax) * 0.5f, s = sqrt(zb); /* exact, then >= 2^-25 or 0 */
  F z = select(zb, xs * xs, small);
  F p = z * (0x1.55554cp-3f + z * (0x1.3338a4p-4f + z * (0x1.6ca968p-5f + z * (0x1.04bbd2p-5f +
        z * (0x1.d6c57cp-7f + z * 0x1.341eb4p-5f)))));
  F r_small = PC_PIO2_HI - (xs - (PC_PIO2_LO - xs * p));
  F df = pc_float_(pc_bits_(s) & 0xfffff000u); /* s to 12 bits: df * df is exact */
  F c = (zb - df * df) / select(s + df, (F)1.0f, s == 0.0f);
  F r_pos = 2.0f * (df + (s * p + c));
  F r_neg = 2.0f * (PC_PIO2_HI - (s + (s * p - PC_PIO2_LO)));
  F r = select(select(r_pos, r_neg, (b >> 31) != 0u), r_small, small);
  return select(r, pc_float_((U)PC_NAN_BITS), ab > 0x3f800000u);
}

/* ---- log, exp2, exp, powr -------------------------------------------------------------------------------
 * pc_log(x): natural log, error <= 1 ulp (0.84 over all floats); log(+-0) = -inf (denormals too), log(x < 0) = NaN, log(+inf) =
 * +inf, NaN -> NaN. x = 2^k (1 + f), sqrt(1/2) <= 1 + f < sqrt(2), s = f / (2 + f):
 * log(1 + f) = f - f^2/2 + s (f^2/2 + z L(z)), z = s^2 <= 0.0295 (L: relative error 2^-35 of the whole). */
static inline PC_OVL F pc_log_poly_(F z) {
  return z * (0x1.555554p-1f + z * (0x1.999c26p-2f + z * (0x1.23d3dap-2f + z * 0x1.f13d2p-3f)));
}
/* For x positive and normal: 1 + f in [sqrt(1/2), sqrt(2)) and k. */
static inline PC_OVL F pc_log_reduce_(F x, F* k) {
  U iy = pc_bits_(x) + (0x3f800000u - 0x3f3504f3u);
  *k = pc_to_float_(pc_int_(iy >> 23) - 127);
  return pc_float_((iy & 0x7fffffu) + 0x3f3504f3u);
}
static inline PC_OVL F pc_log(F x) {
  U b = pc_bits_(x);
  I normal = (b >= 0x00800000u) & (b < 0x7f800000u);
  F k, f = pc_log_reduce_(select((F)1.0f, x, normal), &k) - 1.0f; /* exact */
  F s = f / (2.0f + f), hfsq = 0.5f * f * f;
  /* k ln2_hi is exact: ln2_hi has 16 bits, |k| <= 126 */
  F r = s * (hfsq + pc_log_poly_(s * s)) + k * 0x1.7f7d1cp-20f - hfsq + f + k * 0x1.62e4p-1f;
  r = select(r, (F)(-INFINITY), (b & 0x7fffffffu) < 0x00800000u);
  r = select(r, (F)INFINITY, b == 0x7f800000u);
  return select(r, pc_float_((U)PC_NAN_BITS), (b > 0x7f800000u) & ((b & 0x7fffffffu) >= 0x00800000u));
}
/* 2^(th + tl) for |tl| <= 2^-20 |th| or so; |th| > 200 saturates (to 0 or inf); results below FLT_MIN
 * are +0: the exponent is added in the bits, never by a multiplication that could round. 2^r - 1 on
 * |r| <= 1/2 by a minimax polynomial (relative error 2^-28.3). */
static inline PC_OVL F pc_exp2_dd_(F th, F tl) {
  tl = select(tl, (F)0.0f, fabs(th) > 200.0f);
  th = fmin(fmax(th, -200.0f), 200.0f);
  F n = rint(th), r = (th - n) + tl;
  F p = 1.0f + r * (0x1.62e43p-1f + r * (0x1.ebfbdcp-3f + r * (0x1.c6af7ap-5f + r * (0x1.3b2dd6p-7f +
        r * (0x1.5f095cp-10f + r * 0x1.4176a4p-13f)))));
  I ni = pc_to_int_(n), e = pc_int_(pc_bits_(p) >> 23) + ni; /* the result's biased exponent */
  F res = pc_float_(pc_bits_(p) + (pc_uint_(ni) << 23));
  res = select(res, (F)0.0f, e <= 0);
  return select(res, (F)INFINITY, e >= 255);
}
/* e^x for finite x, through x log2(e) in double-float. */
static inline PC_OVL F pc_exp_finite_(F x) {
  x = fmin(fmax(x, -104.0f), 90.0f);
  F tl, th = pc_two_prod_(x, PC_INV_LN2_HI, &tl);
  return pc_exp2_dd_(th, tl + x * PC_INV_LN2_LO);
}
/* pc_exp2(x), pc_exp(x): error <= 1.5 ulp (1.08, 1.17 over all floats); +inf -> +inf, -inf -> +0,
 * results below FLT_MIN -> +0. */
static inline PC_OVL F pc_exp2(F x) {
  U b = pc_bits_(x), ab = b & 0x7fffffffu;
  F r = pc_exp2_dd_(pc_float_(select(b, b & 0x80000000u, ab < 0x00800000u)), (F)0.0f);
  return select(r, pc_float_((U)PC_NAN_BITS), ab > 0x7f800000u);
}
static inline PC_OVL F pc_exp(F x) {
  U b = pc_bits_(x), ab = b & 0x7fffffffu;
  F r = pc_exp_finite_(pc_float_(select(b, b & 0x80000000u, ab < 0x00800000u)));
  return select(r, pc_float_((U)PC_NAN_BITS), ab > 0x7f800000u);
}
/* log2 x as hi + lo for x positive and normal (relative error about 2^-32): x = 2^k m, m = c (1 + s) /
 * (1 - s) with c = 2^(-1/3), 1 or 2^(1/3) (as floats) nearest to m, so |s| <= 0.058; s = (m - c) /
 * (m + c) in double-float (m - c is exact), log(m / c) = 2 atanh s = 2s + s z L(z). */
static inline PC_OVL F pc_log2_dd_(F x, F* lo) {
  F k, m = pc_log_reduce_(x, &k);
  I below = m < 0x1.c823ep-1f, above = m >= 0x1.1f59acp+0f; /* 2^(-1/6), 2^(1/6) */
  F c = select(select((F)1.0f, (F)0x1.428a3p+0f, above), (F)0x1.965feap-1f, below);
  F c_hi = select(select((F)0.0f, (F)0x1.555558p-2f, above), (F)-0x1.555556p-2f, below);
  F c_lo = select(select((F)0.0f, (F)-0x1.a45606p-27f, above), (F)-0x1.0c3d7ep-27f, below);
  F f = m - c, dl, dh = pc_two_sum_(m, c, &dl);
  F sh = f / dh, pe, p = pc_two_prod_(sh, dh, &pe);
  F sl = (((f - p) - pe) - sh * dl) / dh;
  F a = 2.0f * sh, bb = 2.0f * sl + sh * pc_log_poly_(sh * sh); /* log(m / c) = a + bb */
  F he, h = pc_two_prod_(a, PC_INV_LN2_HI, &he);
  F e1, e2, u = pc_two_sum_(k, c_hi, &e1), hi = pc_two_sum_(u, h, &e2);
  return pc_fast_two_sum_(hi, e2 + (e1 + (c_lo + (he + (a * PC_INV_LN2_LO + bb * PC_INV_LN2_HI)))), lo);
}
/* pc_powr(x, y) = x^y for x >= 0 (OpenCL powr): error <= 2 ulp (1.2 measured on 10^7 pairs, Phong's
 * cos^n with n <= 10^4 and |y log2 x| near 126 among them), as 2^(y log2 x) with log2 x and its
 * product with y in double-float. Special cases as OpenCL's powr: x < 0 -> NaN; powr(x, +-0) = 1 for
 * finite x > 0; powr(+-0, y) = +inf for y < 0 (-inf included), +0 for y > 0; powr(+-0, +-0) = NaN;
 * powr(+inf, +-0) = NaN; powr(+1, y) = 1 for finite y; powr(+1, +-inf) = NaN; NaN -> NaN; otherwise
 * the limits (powr(x < 1, +inf) = +0, powr(+inf, y > 0) = +inf, ...). Results below FLT_MIN -> +0. */
static inline PC_OVL F pc_powr(F x, F y) {
  U xb = pc_bits_(x), yb = pc_bits_(y), ya = yb & 0x7fffffffu;
  xb = select(xb, xb & 0x80000000u, (xb & 0x7fffffffu) < 0x00800000u);
  yb = select(yb, yb & 0x80000000u, ya < 0x00800000u);
  x = pc_float_(xb);
  y = pc_float_(yb);
  I normal = (xb >= 0x00800000u) & (xb < 0x7f800000u); /* x positive, normal */
  F lo, hi = pc_log2_dd_(select((F)1.0f, x, normal), &lo);
  /* |y| <= 2^64 keeps the split exact; beyond it |y log2 x| > 200 (or log2 x = 0) anyway. */
  F yc = fmin(fmax(y, -0x1p64f), 0x1p64f), tl, th = pc_two_prod_(yc, hi, &tl);
  F r = pc_exp2_dd_(th, tl + yc * lo);
  I yzero = y == 0.0f, ypos = (yb >> 31) == 0u;
  r = select(r, select(select((F)INFINITY, (F)0.0f, ypos), pc_float_((U)PC_NAN_BITS), yzero), x == 0.0f);
  r = select(r, select(select((F)0.0f, (F)INFINITY, ypos), pc_float_((U)PC_NAN_BITS), yzero), xb == 0x7f800000u);
  I nan = (xb > 0x80000000u) | ((xb > 0x7f800000u) & (xb < 0x80000000u)) | (ya > 0x7f800000u) |
          ((xb == 0x3f800000u) & (ya == 0x7f800000u));
  return select(r, pc_float_((U)PC_NAN_BITS), nan);
}

/* ---- erf -----------------------------------------------------------------------------------------------
 * pc_erf(x): error <= 2 ulp (1.31 over all floats); erf(+-0) = +-0, erf(+-inf) = +-1, NaN -> NaN.
 * |x| < 1: x + x P(x^2) (relative error 2^-29.4); 1 <= |x| < 4: 1 - e^(G(|x| - 2.5) - x^2) with
 * G = log(erfc(x) e^(x^2)) (error 2^-29.8 in erf); |x| >= 4: 1 (erfc(4) < 2^-25). */
static inline PC_OVL F pc_erf(F x) {
  U b = pc_bits_(x), ab = b & 0x7fffffffu;
  F ax = pc_float_(select(ab, (U)0u, ab < 0x00800000u));
  /* Tiny x: x P(x^2), about x/8, is computed 2^64 times larger so that it is never denormal. */
  I tiny = ax < 0x1p-64f;
  F as = ax * select((F)1.0f, (F)0x1p64f, tiny), z = ax * ax;
  F r = as + as * (0x1.06eba8p-3f + z * (-0x1.81273ep-2f + z * (0x1.ce2ce6p-4f + z * (-0x1.b7f71ap-6f +
        z * (0x1.53f226p-8f + z * (-0x1.a35186p-11f + z * 0x1.4772cp-14f))))));
  r = r * select((F)1.0f, (F)0x1p-64f, tiny);
  I tail = ax >= 1.0f;
  if (pc_any_(tail)) {
    F at = fmin(ax, 4.0f), u = fmax(at, 1.0f) - 2.5f; /* exact */
    F g = -0x1.8e8b9cp+0f + u * (-0x1.69289p-2f + u * (0x1.cbb1a8p-5f + u * (-0x1.5f2ff2p-7f +
          u * (0x1.422ce8p-9f + u * (-0x1.470526p-13f + u * 0x1.85313ep-13f)))));
    r = select(r, 1.0f - pc_exp_finite_(g - at * at), tail);
    r = select(r, (F)1.0f, ax >= 4.0f);
  }
  r = pc_float_(pc_bits_(r) | (b & 0x80000000u));
  return select(r, pc_float_((U)PC_NAN_BITS), ab > 0x7f800000u);
}

#include "templates/lane_width_end.h"
