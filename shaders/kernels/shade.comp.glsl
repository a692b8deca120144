// The integrator: Monte Carlo estimate of reflected radiance for one object's pixels,
//   L_o(V) = 1/N * sum_k f(L_k, V) * L_env(L_k) * max(0, N.L_k) / pdf(L_k),
// with L_k from the sampler of this program (cosine-weighted, uniform, or the BRDF file's own
// sampleBRDF(); all unbiased). Samples that are NaN or Inf are dropped and counted, never accumulated, and the
// pixel's mean divides by the samples kept.
//
// A BRDFA Engine file (BRDFA_LEGACY_RENDER) is run as that engine ran it instead: the pixel is
// the plain average of its render(L, N, V, texCoord, worldToLocal) over uniform hemisphere
// samples, render() doing its own environment lookup and cosine. That is not an estimate of
// L_o (it lacks the 2 pi of the uniform pdf, and whatever the file leaves out); it reproduces
// the engine's images, and such files are marked "legacy" and never analysed.

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

void main() {
  // The dispatch covers the object's screen bounds, starting at the packed origin.
  uvec2 p = gl_GlobalInvocationID.xy + uvec2(brdfa_pc.target.z & 0xffffu, brdfa_pc.target.z >> 16);
  if (p.x >= brdfa_pc.frame.x || p.y >= brdfa_pc.frame.y) return;

  uint pixel = brdfa_pixelIndex(p);
  vec4 gp = brdfa_gPosition(pixel);
  if (uint(abs(gp.w) + 0.5) != brdfa_pc.target.x) return;  // another object, or background
  vec4 gn = brdfa_gNormal(pixel);
  vec4 gt = brdfa_gTangent(pixel);
  texCoord = vec2(gn.w, gt.w);

  // The frame is turned into the environment's frame (see lib/environment.glsl), so samples
  // look the environment up without a per-sample rotation.
  vec3 N = brdfa_toEnvironment(normalize(gn.xyz));
  vec3 V = brdfa_toEnvironment(normalize(brdfa_pc.cameraPos.xyz - gp.xyz));
  // guard: interpolated normals near a silhouette can face slightly away from the viewer;
  // bend N until V is just above the horizon so every BRDF sees a valid outgoing direction.
  float NdotV = dot(N, V);
  if (NdotV < 1e-3) N = normalize(N + V * (1e-3 - NdotV));
  vec3 X, Y;
#if defined(BRDFA_TANGENT_FRAME)
  brdfa_tangentFrame(N, brdfa_toEnvironment(gt.xyz), gp.w < 0.0 ? -1.0 : 1.0, X, Y);
#else
  // The BRDF never reads X or Y (brdf_features.cpp): any orthonormal frame serves the
  // isotropic hemisphere samplers, and this one needs no tangent.
  brdfa_basisFromNormal(N, X, Y);
#endif

  uvec2 rotation = brdfa_pixelRotation(p);
  uint first = brdfa_pc.frame.z;
  uint count = brdfa_pc.frame.w;
  vec3 sum = vec3(0.0);
  uint dropped = 0u;
  for (uint s = 0u; s < count; ++s) {
#if defined(BRDFA_LEGACY_RENDER)
    float unusedWeight;
    vec3 l = brdfa_sampleUniformHemisphere(brdfa_sample2D(rotation, first + s), unusedWeight);
    vec3 L = X * l.x + Y * l.y + N * l.z;
    // Rows X, Y, N: world (environment frame) -> local tangent space.
    vec3 c = render(L, N, V, texCoord, transpose(mat3(X, Y, N)));
#elif defined(BRDFA_SAMPLING_BRDF)
    // The file's own importance sampler: it returns f(L, V) and the solid-angle pdf of L.
    vec3 L;
    float pdf;
    vec3 f = sampleBRDF(brdfa_sample2D(rotation, first + s), V, N, X, Y, L, pdf);
    // guard: pdf = 0 marks a direction the sampler rejected (below the horizon): it
    // contributes 0, and dividing would give 0/0.
    vec3 c = pdf > 0.0 ? f * brdfa_environmentUnit(L) * (max(dot(N, L), 0.0) / pdf) : vec3(0.0);
#else
    float weight;  // cos / pdf
    vec3 l = brdfa_sampleHemisphere(brdfa_sample2D(rotation, first + s), weight);
    vec3 L = X * l.x + Y * l.y + N * l.z;
    vec3 c = BRDF(L, V, N, X, Y) * brdfa_environmentUnit(L) * weight;
#endif
    // guard: a NaN or infinite channel makes the channel sum NaN or infinite, so one test of
    // the sum drops the sample (a finite sum that overflows float is dropped as infinite too).
    float channels = c.x + c.y + c.z;
    if (isnan(channels) || isinf(channels)) {
      ++dropped;
      continue;
    }
    sum += c;
  }
  vec4 value = vec4(sum * brdfa_environmentIntensity(), float(count - dropped));
  if (brdfa_pc.target.w != 0u) {
    // First pass after a restart (always half A): overwrite this pixel's halves instead of
    // adding, so a change of BRDF or parameters needs no clear of the whole buffer.
    brdfa_accum[pixel] = value;
    brdfa_accum[brdfa_halfOffset(1u) + pixel] = vec4(0.0);
  } else {
    brdfa_accum[brdfa_halfOffset(brdfa_pc.target.y) + pixel] += value;
  }
  if (dropped != 0u) atomicAdd(brdfa_nanSamples, dropped);
}
