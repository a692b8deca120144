// Hemisphere sampling in the local frame (z = normal). Each sampler returns the direction and
// its estimator weight cos(theta) / pdf in closed form, so the integrator computes
// f * L_env * cos / pdf (unbiased) without a per-sample division.

const float BRDFA_PI = 3.14159265358979323846;

// Cosine-weighted (Malley's method: uniform disk, projected up; pbrt-v4 SampleCosineHemisphere,
// with the disk by polar mapping). pdf = cos(theta) / pi, so cos / pdf = pi.
vec3 brdfa_sampleCosineHemisphere(vec2 u, out float cosOverPdf) {
  float r = sqrt(u.x);
  float phi = 2.0 * BRDFA_PI * u.y;
  // guard: u.x -> 1 gives z -> 0; max() keeps sqrt off a rounding-negative argument.
  float z = sqrt(max(0.0, 1.0 - u.x));
  // guard: at z = 0 the pdf is 0; that horizon direction has measure zero and contributes 0.
  cosOverPdf = z > 0.0 ? BRDFA_PI : 0.0;
  return vec3(r * cos(phi), r * sin(phi), z);
}

// Uniform over the hemisphere: z = 1 - u.x is uniform on (0, 1]. pdf = 1 / (2 pi), so
// cos / pdf = 2 pi cos(theta).
vec3 brdfa_sampleUniformHemisphere(vec2 u, out float cosOverPdf) {
  float z = 1.0 - u.x;
  float r = sqrt(max(0.0, 1.0 - z * z));  // guard: rounding can push 1 - z^2 below 0
  float phi = 2.0 * BRDFA_PI * u.y;
  cosOverPdf = 2.0 * BRDFA_PI * z;
  return vec3(r * cos(phi), r * sin(phi), z);
}

vec3 brdfa_sampleHemisphere(vec2 u, out float cosOverPdf) {
#if defined(BRDFA_SAMPLING_UNIFORM)
  return brdfa_sampleUniformHemisphere(u, cosOverPdf);
#else
  return brdfa_sampleCosineHemisphere(u, cosOverPdf);
#endif
}
