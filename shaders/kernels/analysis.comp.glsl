// Analysis of a BRDF: evaluates the file's own BRDF() where the host asks, in the
// frame N = +z, X = +x, Y = +y. The host (brdf_analysis.cpp) passes the work in the read-only
// binding 0 (brdfa_gbuffer, unused otherwise by analysis):
//   brdfa_gbuffer[0] = (mode, items, samples per chunk, chunks per view), as uintBitsToFloat;
// mode 0, values: brdfa_gbuffer[1 + 2p] = L, brdfa_gbuffer[2 + 2p] = V of pair p (xyz, unit);
//   invocation p writes brdfa_accum[p] = (f(L, V), 0).
// mode 1, albedo: brdfa_gbuffer[1 + v] = V of view v; invocation j = v * chunks + c draws
//   `samples per chunk` samples of lib/albedo.glsl's estimator, with a random shift of its own
//   (independent replicates), and writes brdfa_accum[j] = (sum of f cos / pdf, non-finite count).
layout(local_size_x = 8, local_size_y = 1, local_size_z = 1) in;

void main() {
  uint j = gl_GlobalInvocationID.x;
  uvec4 header = floatBitsToUint(brdfa_gbuffer[0]);
  uint mode = header.x, items = header.y, perChunk = header.z, chunks = header.w;
  const vec3 N = vec3(0.0, 0.0, 1.0), X = vec3(1.0, 0.0, 0.0), Y = vec3(0.0, 1.0, 0.0);
  texCoord = vec2(0.5);
  if (mode == 0u) {
    if (j >= items) return;
    vec3 L = brdfa_gbuffer[1u + 2u * j].xyz;
    vec3 V = brdfa_gbuffer[2u + 2u * j].xyz;
    brdfa_accum[j] = vec4(BRDF(L, V, N, X, Y), 0.0);
    return;
  }
  if (j >= items * chunks) return;
  vec3 V = brdfa_gbuffer[1u + j / chunks].xyz;
  vec3 sum = vec3(0.0);
  float nonFinite = 0.0;
  brdfa_albedoSamples(V, brdfa_albedoRotation(j), perChunk, sum, nonFinite);
  brdfa_accum[j] = vec4(sum, nonFinite);
}
