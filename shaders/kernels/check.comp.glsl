// Numeric checks of a BRDF (one dispatch per parameter setting). Each invocation takes one view
// direction V of a grid (polar angles up to 89.9 degrees and exactly 90, four azimuths) in the
// frame N = +z, X = +x, Y = +y, and
//  - evaluates f(L, V) and f(V, L) over a grid of light directions with the same polar angles
//    and eight azimuths: counts NaN, Inf and negative values, and the largest relative
//    reciprocity error |f(L,V) - f(V,L)| / max(|f(L,V)|, |f(V,L)|, 1e-6);
//  - estimates the directional albedo E(V) = integral f cos dL with lib/albedo.glsl (the file's
//    sampler, else a cosine + half-vector mixture; 8 replicates of 1024 samples) and its
//    standard error, so the host flags only significant excess over 1.
// L = -V (both on the horizon, opposite azimuths) is left out: the half vector is 0/0 there, a
// configuration of measure zero that the integrator never meets (it is counted apart).
// Output per view (4 vec4):
//   [4v]   = (nan, inf, negative, evaluations)
//   [4v+1] = (albedo, its standard error, reciprocity error, pairs left out)
//   [4v+2] = (grid index t*8+k of the worst reciprocity, its f(L,V), its f(V,L), where the
//             first bad value was: grid index, or 100: an albedo sample; -1: none)
//   [4v+3] = (the first bad value, rgb; its kind: 1 NaN, 2 Inf, 3 negative)
// albedo and error of the channel with the largest albedo; reciprocity values of the channel
// with the largest relative error.
layout(local_size_x = 8, local_size_y = 1, local_size_z = 1) in;

const int BRDFA_THETAS = 10;
const float BRDFA_THETA_DEG[BRDFA_THETAS] = float[](0.0, 15.0, 30.0, 45.0, 60.0, 75.0, 85.0, 89.0, 89.9, 90.0);
const uint BRDFA_VIEWS = 40u;  // 10 polar angles x 4 azimuths
const uint BRDFA_ALBEDO_CHUNKS = 8u;          // independent replicates per view
const uint BRDFA_ALBEDO_CHUNK_SAMPLES = 1024u;

// Exactly on the horizon at 90 degrees: cos(radians(90.0)) is -4e-8 in float, below it.
vec3 brdfa_checkDirection(float thetaDeg, float phi) {
  float s = thetaDeg >= 90.0 ? 1.0 : sin(radians(thetaDeg));
  float z = thetaDeg >= 90.0 ? 0.0 : cos(radians(thetaDeg));
  return vec3(s * cos(phi), s * sin(phi), z);
}

// Counts a bad value, and keeps the first one's place, value and kind.
void brdfa_tally(vec3 f, float where, inout vec3 counts, inout float firstAt, inout vec4 first) {
  float kind = any(isnan(f)) ? 1.0 : any(isinf(f)) ? 2.0 : any(lessThan(f, vec3(0.0))) ? 3.0 : 0.0;
  if (kind == 0.0) return;
  counts[int(kind) - 1] += 1.0;
  if (firstAt < 0.0) {
    firstAt = where;
    first = vec4(f, kind);
  }
}

bool brdfa_finite(vec3 f) { return !any(isnan(f)) && !any(isinf(f)); }

void main() {
  uint v = gl_GlobalInvocationID.x;
  if (v >= BRDFA_VIEWS) return;
  const vec3 N = vec3(0.0, 0.0, 1.0), X = vec3(1.0, 0.0, 0.0), Y = vec3(0.0, 1.0, 0.0);
  vec3 V = brdfa_checkDirection(BRDFA_THETA_DEG[v % 10u], radians(45.0) * float(v / 10u));
  texCoord = vec2(0.5);

  vec3 counts = vec3(0.0);
  float evaluations = 0.0, leftOut = 0.0;
  float reciprocity = 0.0, worstAt = -1.0, worstA = 0.0, worstB = 0.0;
  float firstAt = -1.0;
  vec4 first = vec4(0.0);
  for (int t = 0; t < BRDFA_THETAS; ++t) {
    for (int k = 0; k < 8; ++k) {
      vec3 L = brdfa_checkDirection(BRDFA_THETA_DEG[t], radians(45.0) * float(k));
      // Measure zero, never met by the integrator: L = -V on the horizon (H = 0/0).
      if (length(L + V) < 1e-4) {
        leftOut += 1.0;
        continue;
      }
      float at = float(t * 8 + k);
      vec3 a = BRDF(L, V, N, X, Y);
      vec3 b = BRDF(V, L, N, X, Y);
      brdfa_tally(a, at, counts, firstAt, first);
      brdfa_tally(b, at, counts, firstAt, first);
      evaluations += 2.0;
      if (brdfa_finite(a) && brdfa_finite(b)) {
        vec3 scale = max(max(abs(a), abs(b)), vec3(1e-6));  // guard: both ~0 is no error
        vec3 rel = abs(a - b) / scale;
        int c = rel.x >= rel.y && rel.x >= rel.z ? 0 : (rel.y >= rel.z ? 1 : 2);
        if (rel[c] > reciprocity) {
          reciprocity = rel[c];
          worstAt = at;
          worstA = a[c];
          worstB = b[c];
        }
      }
    }
  }

  // Albedo: BRDFA_ALBEDO_CHUNKS independent randomised replicates of lib/albedo.glsl's
  // estimator; the spread of their means is the standard error.
  vec3 chunkSum = vec3(0.0), chunkSumSq = vec3(0.0);
  float nonFinite = 0.0;
  for (uint k = 0u; k < BRDFA_ALBEDO_CHUNKS; ++k) {
    vec3 sum = vec3(0.0);
    uint j = v * BRDFA_ALBEDO_CHUNKS + k;
    brdfa_albedoSamples(V, brdfa_albedoRotation(j), BRDFA_ALBEDO_CHUNK_SAMPLES, sum, nonFinite);
    vec3 m = sum / float(BRDFA_ALBEDO_CHUNK_SAMPLES);
    chunkSum += m;
    chunkSumSq += m * m;
  }
  evaluations += float(BRDFA_ALBEDO_CHUNKS * BRDFA_ALBEDO_CHUNK_SAMPLES);
  if (nonFinite > 0.0) {
    counts.x += nonFinite;  // NaN or Inf from an albedo sample
    if (firstAt < 0.0) {
      firstAt = 100.0;
      first = vec4(0.0, 0.0, 0.0, 1.0);
    }
  }
  float n = float(BRDFA_ALBEDO_CHUNKS);
  vec3 mean = chunkSum / n;
  vec3 stderr = sqrt(max(chunkSumSq / n - mean * mean, vec3(0.0)) / (n - 1.0));
  int c = mean.x >= mean.y && mean.x >= mean.z ? 0 : (mean.y >= mean.z ? 1 : 2);
  brdfa_accum[4u * v] = vec4(counts, evaluations);
  brdfa_accum[4u * v + 1u] = vec4(mean[c], stderr[c], reciprocity, leftOut);
  brdfa_accum[4u * v + 2u] = vec4(worstAt, worstA, worstB, firstAt);
  brdfa_accum[4u * v + 3u] = first;
}
