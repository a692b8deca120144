// Checks a BRDF file's sampleBRDF() against itself and against BRDF(). One invocation draws a
// chunk of samples for one view direction V (frame N = +z, X = +x, Y = +y):
//  - bins each drawn L into 8 x 16 cells of equal solid angle (uniform in cos(theta) and phi)
//    and sums 1/pdf and 1/pdf^2 per cell: if pdf is the density of the samples, the mean of
//    1_cell / pdf is the cell's solid angle, 2 pi / 128 (the host tests this per cell);
//  - sums f cos / pdf (importance-sampled albedo, channel of largest value) and the same from
//    cosine-weighted samples of BRDF(), whose means must agree;
//  - records the largest relative difference between the returned value and BRDF(L, V).
// Output (vec4) per invocation: 128 cells (count, sum 1/pdf, sum 1/pdf^2, 0), then
// (rejected, mismatch, albedo sum, albedo sum of squares), then (cosine albedo sum, its sum of
// squares, 0, 0).
layout(local_size_x = 8, local_size_y = 1, local_size_z = 1) in;

const uint BRDFA_CELLS = 128u;
const uint BRDFA_STRIDE = BRDFA_CELLS + 2u;
const uint BRDFA_CHUNKS = 32u;          // invocations per view
const uint BRDFA_CHUNK_SAMPLES = 2048u;
const float BRDFA_VIEW_DEG[4] = float[](0.0, 30.0, 60.0, 80.0);

float brdfa_largest(vec3 v) { return max(v.x, max(v.y, v.z)); }

void main() {
  uint id = gl_GlobalInvocationID.x;
  if (id >= 4u * BRDFA_CHUNKS) return;
  uint view = id / BRDFA_CHUNKS, chunk = id % BRDFA_CHUNKS;
  const vec3 N = vec3(0.0, 0.0, 1.0), X = vec3(1.0, 0.0, 0.0), Y = vec3(0.0, 1.0, 0.0);
  float tv = radians(BRDFA_VIEW_DEG[view]);
  vec3 V = vec3(sin(tv), 0.0, cos(tv));
  texCoord = vec2(0.5);
  uint base = id * BRDFA_STRIDE;
  for (uint c = 0u; c < BRDFA_CELLS; ++c) brdfa_accum[base + c] = vec4(0.0);

  float rejected = 0.0, mismatch = 0.0, albedo = 0.0, albedoSq = 0.0, cosAlbedo = 0.0, cosAlbedoSq = 0.0;
  uvec2 rotation = brdfa_pixelRotation(uvec2(id, 7u));  // chunks see different sample points
  for (uint i = 0u; i < BRDFA_CHUNK_SAMPLES; ++i) {
    vec2 u = brdfa_sample2D(rotation, i);
    vec3 L;
    float pdf;
    vec3 f = sampleBRDF(u, V, N, X, Y, L, pdf);
    if (!(pdf > 0.0) || L.z <= 0.0 || isinf(pdf)) {
      rejected += 1.0;
    } else {
      vec3 g = BRDF(L, V, N, X, Y);
      vec3 scale = max(max(abs(f), abs(g)), vec3(1e-6));  // guard: both ~0 is no mismatch
      mismatch = max(mismatch, brdfa_largest(abs(f - g) / scale));
      float phi = atan(L.y, L.x);                            // -pi..pi
      uint ct = min(uint(L.z * 8.0), 7u);
      uint cp = min(uint((phi + BRDFA_PI) / (2.0 * BRDFA_PI) * 16.0), 15u);
      uint cell = base + ct * 16u + cp;
      float inv = 1.0 / pdf;
      brdfa_accum[cell] += vec4(1.0, inv, inv * inv, 0.0);
      float w = brdfa_largest(f) * L.z * inv;
      albedo += w;
      albedoSq += w * w;
    }
    float cosOverPdf;
    vec3 lc = brdfa_sampleCosineHemisphere(u, cosOverPdf);
    float wc = brdfa_largest(BRDF(lc, V, N, X, Y)) * cosOverPdf;
    cosAlbedo += wc;
    cosAlbedoSq += wc * wc;
  }
  brdfa_accum[base + BRDFA_CELLS] = vec4(rejected, mismatch, albedo, albedoSq);
  brdfa_accum[base + BRDFA_CELLS + 1u] = vec4(cosAlbedo, cosAlbedoSq, 0.0, 0.0);
}
