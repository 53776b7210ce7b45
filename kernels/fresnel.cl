/* Fresnel reflectance of smooth interfaces, unpolarised light. */
#ifndef PATHCL_FRESNEL_CL
#define PATHCL_FRESNEL_CL

/* Dielectric: cos_i > 0 on the incident side, eta = n_transmitted / n_incident. 1 under total internal
 * reflection. */
inline float fresnel_dielectric(float cos_i, float eta) {
  cos_i = clamp(cos_i, 0.0f, 1.0f);
  float sin2_t = (1.0f - cos_i * cos_i) / (eta * eta);
  if (sin2_t >= 1.0f) return 1.0f;
  float cos_t = sqrt(fmax(0.0f, 1.0f - sin2_t));
  float r_parallel = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
  float r_perpendicular = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
  return 0.5f * (r_parallel * r_parallel + r_perpendicular * r_perpendicular);
}

/* Conductor with complex index eta + i k per channel, from a medium of index 1 (pbrt-v3 FrConductor). */
inline float3 fresnel_conductor(float cos_i, float3 eta, float3 k) {
  cos_i = clamp(cos_i, 0.0f, 1.0f);
  float cos2 = cos_i * cos_i, sin2 = 1.0f - cos2;
  float3 t0 = eta * eta - k * k - sin2;
  float3 a2_plus_b2 = sqrt(fmax(t0 * t0 + 4.0f * eta * eta * k * k, 0.0f));
  float3 t1 = a2_plus_b2 + cos2;
  float3 a = sqrt(fmax(0.5f * (a2_plus_b2 + t0), 0.0f));
  float3 t2 = 2.0f * cos_i * a;
  /* Both are squared magnitudes in [0, 1]. Where the index is that of the medium (eta 1, k 0: the
   * "specular": 0 channel) t1 and t2 are equal up to rounding, and their difference, negative half the
   * time, made negative radiance. */
  float3 rs = clamp((t1 - t2) / (t1 + t2), 0.0f, 1.0f);
  float3 t3 = cos2 * a2_plus_b2 + sin2 * sin2;
  float3 t4 = t2 * sin2;
  float3 rp = rs * clamp((t3 - t4) / (t3 + t4), 0.0f, 1.0f);
  return 0.5f * (rp + rs);
}

/* Mirror reflection and refraction in the local frame (normal +z). */
inline float3 reflect_local(float3 wo) { return (float3)(-wo.x, -wo.y, wo.z); }

/* Refraction of wo through the interface with normal n on wo's side; eta = n_t / n_i. false under total
 * internal reflection. */
inline bool refract_dir(float3 wo, float3 n, float eta, float3* wt) {
  float cos_i = pc_dot(wo, n);
  float sin2_t = (1.0f - cos_i * cos_i) / (eta * eta);
  if (sin2_t >= 1.0f) return false;
  float cos_t = sqrt(1.0f - sin2_t);
  *wt = pc_normalize(-wo / eta + (cos_i / eta - cos_t) * n);
  return true;
}

#endif
