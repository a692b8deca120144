// Directional albedo E(V) = integral over the hemisphere of f(L, V) (N.L) dL, by Monte Carlo in
// the frame N = +z, X = +x, Y = +y. Used by the analysis kernel (the albedo curve)
// and by the check kernel (energy conservation), so both report the same estimate.
//
// Estimators (each unbiased for the integral of the BRDF() the renderer shades with):
//  - the file has a sampler: importance sampling with its own sampleBRDF() (f cos / pdf). For
//    microfacet files the NDF cancels between f and pdf, so a lobe as sharp as GGX at roughness
//    0.001 (a width of 1e-3 rad) is integrated as accurately as a broad one. A draw with pdf 0
//    (rejected, reflected below the horizon) contributes 0, as its density says.
//  - otherwise: a deterministic mixture (Veach 1997, balance heuristic) of cosine-weighted
//    directions and of half vectors H drawn log-uniformly in sin(theta_h) over [1e-6, 1]
//    (mirrored about H: L = 2 (V.H) H - V). The half-vector part is scale free: a
//    specular lobe of any width between 1e-6 and 1 rad around the mirror direction gets a fixed
//    share of the draws (about 1/14 per factor e of width), so a sharp lobe is not missed as a
//    cosine grid misses it (the 58 that a 4096-sample cosine estimate gave for GGX at 0.001).
// The caller runs independent randomised chunks (a random shift of the R2 sequence each) and
// takes the spread of their means as the standard error: randomised QMC replicates.

// The half vector's sine s = sin(theta_h) is drawn log-uniformly in [1e-6, 1]: density
// 1 / (s ln(1e6)) in s. With dw_H = s ds dphi / cos(theta_h), its density in solid angle is
// p_H = cos(theta_h) / (2 pi s^2 ln(1e6)): no inverse trigonometry, which is inexact on some
// drivers for tiny angles, where this density is largest.
const float BRDFA_LOG_H_MIN = 1e-6;     // smallest sin(theta_h) drawn
const float BRDFA_LOG_H_SPAN = 13.815511;  // ln(1 / BRDFA_LOG_H_MIN)

// Density in solid angle of L under the log-polar half-vector draw for view V (0 where it never
// lands): p_H(H) / (4 V.H) (Walter 2007 eq. 14 for the Jacobian of the reflection).
float brdfa_logHalfVectorPdf(vec3 L, vec3 V) {
  vec3 h = L + V;
  if (dot(h, h) <= 0.0) return 0.0;  // guard: L = -V has no half vector (measure zero)
  vec3 H = normalize(h);
  float vh = dot(V, H);
  if (vh <= 0.0 || H.z <= 0.0) return 0.0;  // never drawn: the draw keeps V.H > 0 and H up
  float s = length(H.xy);  // sin(theta_h), accurate near the pole where 1 - H.z is not
  if (s < BRDFA_LOG_H_MIN) return 0.0;  // guard: below the drawn range (covered by cosine)
  return H.z / (2.0 * BRDFA_PI * s * s * BRDFA_LOG_H_SPAN * 4.0 * vh);
}

// Draws L by the log-polar half-vector rule, with its density `pdf` computed from the drawn H
// itself: recomputing H from L + V loses the small sin(theta_h) to cancellation at grazing
// views (L.x + V.x of two near-opposite unit vectors), and 1 / s^2 turns that rounding into a
// bias (+0.7% at 89 degrees). Returns false when the mirrored direction does not exist
// (V.H <= 0), which counts as a draw of value 0.
bool brdfa_sampleLogHalfVector(vec2 u, vec3 V, out vec3 L, out float pdf) {
  float s = BRDFA_LOG_H_MIN * exp(u.x * BRDFA_LOG_H_SPAN);
  float phi = 2.0 * BRDFA_PI * u.y;
  vec3 H = vec3(s * cos(phi), s * sin(phi), sqrt(max(0.0, 1.0 - s * s)));  // guard: rounding past 1
  float vh = dot(V, H);
  L = 2.0 * vh * H - V;
  pdf = vh > 0.0 ? H.z / (2.0 * BRDFA_PI * s * s * BRDFA_LOG_H_SPAN * 4.0 * vh) : 0.0;
  return vh > 0.0;
}

// The random shift of replicate `j`'s R2 sequence: replicates are independent estimates.
uvec2 brdfa_albedoRotation(uint j) {
  return uvec2(brdfa_hash(j * 0x9e3779b9u + 0x632be5abu), brdfa_hash(j ^ 0x85ebca6bu));
}

bool brdfa_albedoFinite(vec3 f) { return !any(isnan(f)) && !any(isinf(f)); }

// Adds `count` samples of f cos / pdf for view V, the first `count` points of the R2 sequence
// shifted by `rotation`. Non-finite values are counted in `nonFinite` and left out.
void brdfa_albedoSamples(vec3 V, uvec2 rotation, uint count, inout vec3 sum, inout float nonFinite) {
  const vec3 N = vec3(0.0, 0.0, 1.0), X = vec3(1.0, 0.0, 0.0), Y = vec3(0.0, 1.0, 0.0);
  for (uint i = 0u; i < count; ++i) {
    vec2 u = brdfa_sample2D(rotation, i);
    vec3 w = vec3(0.0);
#if defined(BRDFA_HAS_SAMPLER)
    vec3 L;
    float pdf;
    vec3 f = sampleBRDF(u, V, N, X, Y, L, pdf);
    if (!(pdf > 0.0) || L.z <= 0.0) continue;  // rejected draw: value 0
    w = f * (L.z / pdf);
#else
    // Even points from the cosine rule, odd ones from the half-vector rule; each sample is
    // weighted by the mixture's density (balance heuristic with equal counts).
    vec3 L;
    float halfPdf;
    if ((i & 1u) == 0u) {
      float cosOverPdf;
      L = brdfa_sampleCosineHemisphere(u, cosOverPdf);
      halfPdf = brdfa_logHalfVectorPdf(L, V);
    } else if (!brdfa_sampleLogHalfVector(u, V, L, halfPdf)) {
      continue;
    }
    if (L.z <= 0.0) continue;  // below the horizon: f cos = 0
    float pdf = 0.5 * (L.z / BRDFA_PI) + 0.5 * halfPdf;
    if (!(pdf > 0.0)) continue;
    vec3 f = BRDF(L, V, N, X, Y);
    w = f * (L.z / pdf);
#endif
    if (!brdfa_albedoFinite(w)) {
      nonFinite += 1.0;
      continue;
    }
    sum += w;
  }
}
