// The first look at a program not yet run, on a device that compiles a pipeline at its first
// dispatch (lavapipe's JIT: 250-350 ms for a mis program; LocalRenderer::shadeKernels).
// A preview (RenderSettings::previewPass) by this small program is on screen while the scene's
// own program compiles: the estimate of
//   L_o(V) = int f(L, V) L_env(L) max(0, N.L) dL
// from one cosine-weighted direction (cos / pdf = pi) over the coarse environment of
// lib/environment_preview.glsl (the same integral, its lights spread over a coarse cell, so the
// sharpest highlights blur), at one pixel of each 2x2 block, written to the block's pixels this
// object covers, as a preview by the program is (half A the sample, half B none). A first sample
// (RenderSettings::firstSampleKernel) is the same at every pixel over the exact environment: a
// 1-sample estimate of the image, replaced by the first pass of the scene's own program.
//
// In three dispatches of one grid, so that the BRDF's own program is as small as it can be
// (its driver compile is the cost this exists to cut; every line around the BRDF call added
// to it, ~60 ms for the frame, sample and environment lookup, ~40 ms for the block's loads and
// stores):
//  1. kernels/preview_setup.comp.glsl, fixed: the block's pixels, frame, direction and incoming
//     radiance, into the preview scratch (lib/bindings.glsl);
//  2. this program: f(L, V) times the incoming radiance, the only stage that holds the BRDF;
//  3. kernels/preview_scatter.comp.glsl, fixed: the value to the block's covered pixels.
// The next pass, by the scene's program, overwrites it. A sample that is NaN or Inf is dropped,
// as in kernels/shade.comp.glsl; a preview counts in no statistic.

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

void main() {
  uint slot = brdfa_previewSlot();
  uvec4 xMask = brdfa_previewScratch[slot + 2u];
  if (xMask.w == 0u) return;  // nothing of this object in the block (stage 1)
  vec4 n = uintBitsToFloat(brdfa_previewScratch[slot]), v = uintBitsToFloat(brdfa_previewScratch[slot + 1u]);
  vec3 Y = uintBitsToFloat(brdfa_previewScratch[slot + 3u].xyz), L = uintBitsToFloat(brdfa_previewScratch[slot + 4u].xyz);
  vec3 incoming = uintBitsToFloat(brdfa_previewScratch[slot + 5u].xyz);
  texCoord = vec2(n.w, v.w);
  vec3 c = BRDF(L, v.xyz, n.xyz, uintBitsToFloat(xMask.xyz), Y) * incoming;
  // NaN or infinite: dropped, a kept count of 0 (lib/shade_pixel.glsl).
  brdfa_previewScratch[slot + 5u] = brdfa_sampleKept(c) ? uvec4(floatBitsToUint(c), floatBitsToUint(1.0)) : uvec4(0u);
}
