// Checks a BRDF file's sampleBRDF() against itself and against BRDF(), in many configurations
// (a shading frame N, X, Y and a view direction V). The host chooses the configurations
// (brdf_check.cpp) and passes them in the read-only binding 0 (brdfa_gbuffer, unused otherwise
// by the checks):
//   brdfa_gbuffer[0] = (configurations, chunks per configuration, samples per chunk, 0), as
//                      uintBitsToFloat;
//   brdfa_gbuffer[1 + 4c .. 4 + 4c] = N, X, Y, V of configuration c (xyz; X, Y orthonormal
//                      around N, V unit).
// One sampling invocation draws a chunk of samples for one configuration:
//  - bins each drawn L into 8 x 16 cells of equal solid angle (uniform in cos(theta) and phi,
//    both in the frame X, Y, N) and sums 1/pdf and 1/pdf^2 per cell: if pdf is the density of
//    the samples, the mean of 1_cell / pdf is the cell's solid angle, 2 pi / 128 (the host
//    tests this per cell);
//  - sums f cos / pdf (importance-sampled albedo, channel of largest value) and the same from
//    cosine-weighted samples of BRDF(), whose means must agree;
//  - records the largest relative difference between the returned value and BRDF(L, V);
//  - records the largest | |L| - 1 | over draws with pdf > 0 (every drawn L must be unit length),
//    and counts the draws that return pdf > 0 for an L on or below the horizon (N.L <= 0).
// With BRDFA_HAS_PDF (the sample section defines pdfBRDF(L, V, N, X, Y)), also the chi-square
// test of pbrt-v4 (src/pbrt/bsdfs_test.cpp) on the hemisphere:
//  - draws a second sample per iteration, from independent uniform numbers (hash of a counter),
//    and counts the accepted ones per cell of a 10 x 20 grid uniform in theta in [0, pi/2] and
//    phi in [-pi, pi) (cell = theta row * 20 + phi column; frame X, Y, N);
//  - records the largest relative difference between the pdf those samples returned and
//    pdfBRDF(L, V);
//  - further invocations (after the sampling ones), one per 4 cells and configuration,
//    integrate pdfBRDF(L, V) sin(theta) dtheta dphi over each cell by composite 2D Simpson:
//    each cell's probability. The host turns both into a chi-square statistic per configuration.
// Output (vec4) per sampling invocation: 128 cells (count, sum 1/pdf, sum 1/pdf^2, 0), then
// (rejected, mismatch, albedo sum, albedo sum of squares), then (cosine albedo sum, its sum of
// squares, pdf mismatch, 0), then (largest length error, pdf > 0 below the horizon, 0, 0), then
// the 200 chi-square cell counts, four to a vec4. After all sampling invocations: per
// configuration, the 200 cell probabilities, four to a vec4 (written only with BRDFA_HAS_PDF).
layout(local_size_x = 8, local_size_y = 1, local_size_z = 1) in;

const uint BRDFA_CELLS = 128u;
const uint BRDFA_SUMMARY = 3u;                                 // summary vec4s per invocation
const uint BRDFA_CHI2_THETA = 10u, BRDFA_CHI2_PHI = 20u;       // chi-square grid
const uint BRDFA_CHI2_CELLS = BRDFA_CHI2_THETA * BRDFA_CHI2_PHI;
const uint BRDFA_CHI2_VEC4S = BRDFA_CHI2_CELLS / 4u;
const uint BRDFA_STRIDE = BRDFA_CELLS + BRDFA_SUMMARY + BRDFA_CHI2_VEC4S;
const uint BRDFA_SIMPSON = 32u;         // Simpson intervals per dimension and cell (even; 16 was too coarse at 89-degree views)
const float BRDFA_LENGTH_ERROR_CAP = 1e6;  // a NaN or huge length error is recorded as this

float brdfa_largest(vec3 v) { return max(v.x, max(v.y, v.z)); }

uint brdfa_inputUint(uint k) { return floatBitsToUint(brdfa_gbuffer[0][k]); }

// | |L| - 1 |, with NaN and inf recorded as the cap.
float brdfa_lengthError(vec3 L) {
  float d = abs(length(L) - 1.0);
  return d <= BRDFA_LENGTH_ERROR_CAP ? d : BRDFA_LENGTH_ERROR_CAP;
}

#if defined(BRDFA_HAS_PDF)
// The probability that sampleBRDF draws L in chi-square cell `cell` for view V: the integral of
// pdfBRDF(L, V) sin(theta) over the cell's theta x phi rectangle, by composite Simpson with
// BRDFA_SIMPSON intervals in each dimension (weights 1 4 2 4 ... 2 4 1, times h/3 per axis).
float brdfa_cellProbability(uint cell, vec3 V, vec3 N, vec3 X, vec3 Y) {
  const float dTheta = 0.5 * BRDFA_PI / float(BRDFA_CHI2_THETA), dPhi = 2.0 * BRDFA_PI / float(BRDFA_CHI2_PHI);
  float theta0 = float(cell / BRDFA_CHI2_PHI) * dTheta;
  float phi0 = -BRDFA_PI + float(cell % BRDFA_CHI2_PHI) * dPhi;
  float ht = dTheta / float(BRDFA_SIMPSON), hp = dPhi / float(BRDFA_SIMPSON);
  float sum = 0.0;
  for (uint i = 0u; i <= BRDFA_SIMPSON; ++i) {
    float wi = (i == 0u || i == BRDFA_SIMPSON) ? 1.0 : ((i & 1u) == 1u ? 4.0 : 2.0);
    float theta = theta0 + float(i) * ht;
    float st = sin(theta), ct = cos(theta);
    float row = 0.0;
    for (uint j = 0u; j <= BRDFA_SIMPSON; ++j) {
      float wj = (j == 0u || j == BRDFA_SIMPSON) ? 1.0 : ((j & 1u) == 1u ? 4.0 : 2.0);
      float phi = phi0 + float(j) * hp;
      vec3 L = X * (st * cos(phi)) + Y * (st * sin(phi)) + N * ct;
      row += wj * pdfBRDF(L, V, N, X, Y);
    }
    sum += wi * st * row;
  }
  return sum * (ht / 3.0) * (hp / 3.0);
}
#endif

void main() {
  uint id = gl_GlobalInvocationID.x;
  const uint configs = brdfa_inputUint(0u), chunks = brdfa_inputUint(1u), chunkSamples = brdfa_inputUint(2u);
  const uint samplingInvocations = configs * chunks;
  texCoord = vec2(0.5);
  if (id >= samplingInvocations) {
#if defined(BRDFA_HAS_PDF)
    uint e = id - samplingInvocations;  // expected-probability invocation
    if (e >= configs * BRDFA_CHI2_VEC4S) return;
    uint c = e / BRDFA_CHI2_VEC4S, first = 4u * (e % BRDFA_CHI2_VEC4S);
    vec3 N = brdfa_gbuffer[1u + 4u * c].xyz, X = brdfa_gbuffer[2u + 4u * c].xyz;
    vec3 Y = brdfa_gbuffer[3u + 4u * c].xyz, V = brdfa_gbuffer[4u + 4u * c].xyz;
    vec4 p;
    for (uint k = 0u; k < 4u; ++k) p[k] = brdfa_cellProbability(first + k, V, N, X, Y);
    brdfa_accum[samplingInvocations * BRDFA_STRIDE + e] = p;
#endif
    return;
  }
  uint c = id / chunks;
  vec3 N = brdfa_gbuffer[1u + 4u * c].xyz, X = brdfa_gbuffer[2u + 4u * c].xyz;
  vec3 Y = brdfa_gbuffer[3u + 4u * c].xyz, V = brdfa_gbuffer[4u + 4u * c].xyz;
  uint base = id * BRDFA_STRIDE;
  for (uint k = 0u; k < BRDFA_STRIDE; ++k) brdfa_accum[base + k] = vec4(0.0);
  uint histogram = base + BRDFA_CELLS + BRDFA_SUMMARY;
  float pdfMismatch = 0.0, lengthError = 0.0, belowHorizon = 0.0;

  float rejected = 0.0, mismatch = 0.0, albedo = 0.0, albedoSq = 0.0, cosAlbedo = 0.0, cosAlbedoSq = 0.0;
  uvec2 rotation = brdfa_pixelRotation(uvec2(id, 7u));  // chunks see different sample points
  for (uint i = 0u; i < chunkSamples; ++i) {
    vec2 u = brdfa_sample2D(rotation, i);
    vec3 L;
    float pdf;
    vec3 f = sampleBRDF(u, V, N, X, Y, L, pdf);
    float NoL = dot(N, L);
    if (pdf > 0.0) {
      lengthError = max(lengthError, brdfa_lengthError(L));
      if (!(NoL > 0.0)) belowHorizon += 1.0;
    }
    if (!(pdf > 0.0) || !(NoL > 0.0) || isinf(pdf)) {
      rejected += 1.0;
    } else {
      vec3 g = BRDF(L, V, N, X, Y);
      vec3 scale = max(max(abs(f), abs(g)), vec3(1e-6));  // guard: both ~0 is no mismatch
      mismatch = max(mismatch, brdfa_largest(abs(f - g) / scale));
      float phi = atan(dot(L, Y), dot(L, X));               // -pi..pi
      uint ct = min(uint(NoL * 8.0), 7u);
      uint cp = min(uint((phi + BRDFA_PI) / (2.0 * BRDFA_PI) * 16.0), 15u);
      uint cell = base + ct * 16u + cp;
      float inv = 1.0 / pdf;
      brdfa_accum[cell] += vec4(1.0, inv, inv * inv, 0.0);
      float w = brdfa_largest(f) * NoL * inv;
      albedo += w;
      albedoSq += w * w;
    }
#if defined(BRDFA_HAS_PDF)
    // The chi-square draw, from independent uniform numbers: the test's null distribution is
    // that of multinomial counts, and the low-discrepancy points above fall far more evenly
    // (every correct sampler would score p ~ 1, which says nothing).
    uint counter = (id * chunkSamples + i) * 2u;  // unique per (invocation, sample, axis)
    vec2 ui = vec2(uvec2(brdfa_hash(counter ^ 0x3c6ef372u), brdfa_hash((counter + 1u) ^ 0x3c6ef372u)) >> 8u) *
              (1.0 / 16777216.0);                       // 24 bits: exact in float, never 1.0
    vec3 Li;
    float pdfi;
    sampleBRDF(ui, V, N, X, Y, Li, pdfi);
    float NoLi = dot(N, Li);
    if (pdfi > 0.0) {
      lengthError = max(lengthError, brdfa_lengthError(Li));
      if (!(NoLi > 0.0)) belowHorizon += 1.0;
    }
    if (pdfi > 0.0 && NoLi > 0.0 && !isinf(pdfi)) {    // accepted, as above; the rest are rejected draws
      float q = pdfBRDF(Li, V, N, X, Y);
      float d = abs(pdfi - q) / max(pdfi, abs(q));     // pdfi > 0 here: no division by zero
      if (!(d <= 2.0)) d = 2.0;                        // guard: a NaN or inf pdfBRDF counts as the worst
      pdfMismatch = max(pdfMismatch, d);
      vec2 t = vec2(dot(Li, X), dot(Li, Y));
      float theta = atan(length(t), NoLi);             // in [0, pi/2) for NoLi > 0; exact near the pole
      float phii = atan(t.y, t.x);                     // -pi..pi
      // guard (both min): phi = pi, or rounding, would index one past the last row / column
      uint t2 = min(uint(theta / (0.5 * BRDFA_PI) * float(BRDFA_CHI2_THETA)), BRDFA_CHI2_THETA - 1u);
      uint p2 = min(uint((phii + BRDFA_PI) / (2.0 * BRDFA_PI) * float(BRDFA_CHI2_PHI)), BRDFA_CHI2_PHI - 1u);
      uint k2 = t2 * BRDFA_CHI2_PHI + p2;
      brdfa_accum[histogram + k2 / 4u][k2 % 4u] += 1.0;
    }
#endif
    float cosOverPdf;
    vec3 lc = brdfa_sampleCosineHemisphere(u, cosOverPdf);
    float wc = brdfa_largest(BRDF(X * lc.x + Y * lc.y + N * lc.z, V, N, X, Y)) * cosOverPdf;
    cosAlbedo += wc;
    cosAlbedoSq += wc * wc;
  }
  brdfa_accum[base + BRDFA_CELLS] = vec4(rejected, mismatch, albedo, albedoSq);
  brdfa_accum[base + BRDFA_CELLS + 1u] = vec4(cosAlbedo, cosAlbedoSq, pdfMismatch, 0.0);
  brdfa_accum[base + BRDFA_CELLS + 2u] = vec4(lengthError, belowHorizon, 0.0, 0.0);
}
