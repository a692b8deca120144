// The first look at a program not yet run, on a device that compiles a pipeline at its first
// dispatch (lavapipe's JIT: 250-350 ms for a mis program; RendererImpl::shadeKernels).
// A preview (RenderSettings::previewPass) from this small program is on screen while the
// scene's own program compiles: the estimate of
//   L_o(V) = int f(L, V) L_env(L) max(0, N.L) dL
// from frame.w cosine-weighted directions (cos / pdf = pi) over the coarse environment of
// lib/environment_preview.glsl (the same integral, its lights spread over a coarse cell, so the
// sharpest highlights blur), at one pixel of each 2x2 block and written to the block's pixels
// this object covers, as a preview by the program is (half A the even samples, half B the odd
// ones). No sampling table, file sampler, MIS or cube lookup, no loops over the block and no
// read of the accumulators: each adds to the driver's compile, which is the cost this program
// exists to avoid (the shade kernel's block loops and accumulate alone compiled for ~100 ms).
// The next pass, by the scene's program, overwrites it. Samples that are NaN or Inf are
// dropped, as in kernels/shade.comp.glsl; a preview counts in no statistic.

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

void main() {
  uvec2 base = brdfa_dispatchPixel(2u);
  if (base.x >= brdfa_pc.frame.x || base.y >= brdfa_pc.frame.y) return;
  // The block's pixels (clamped into the image: a clamped one is never written), their
  // surfaces, and which of them are this object's.
  uvec2 last = brdfa_pc.frame.xy - 1u;
  uint i0 = brdfa_pixelIndex(base), i1 = brdfa_pixelIndex(min(base + uvec2(1u, 0u), last));
  uint i2 = brdfa_pixelIndex(min(base + uvec2(0u, 1u), last)), i3 = brdfa_pixelIndex(min(base + uvec2(1u, 1u), last));
  uvec2 s0 = brdfa_gSurface(i0), s1 = brdfa_gSurface(i1), s2 = brdfa_gSurface(i2), s3 = brdfa_gSurface(i3);
  uint id = brdfa_pc.target.x;
  bool right = base.x < last.x, below = base.y < last.y;
  bool c0 = brdfa_objectId(s0) == id, c1 = right && brdfa_objectId(s1) == id;
  bool c2 = below && brdfa_objectId(s2) == id, c3 = right && below && brdfa_objectId(s3) == id;
  if (!(c0 || c1 || c2 || c3)) return;
  // The first covered pixel is shaded.
  uvec2 p = c0 ? base : c1 ? base + uvec2(1u, 0u) : c2 ? base + uvec2(0u, 1u) : base + uvec2(1u, 1u);
  uvec2 surface = c0 ? s0 : c1 ? s1 : c2 ? s2 : s3;
  vec3 N, V, X, Y;
  brdfa_surfaceFrame(p, surface, N, V, X, Y);
  brdfa_environmentBegin();
  uint seed = brdfa_pc.target.y;
  uvec4 rotationA = brdfa_halfRotation(p, 0u, seed), rotationB = brdfa_halfRotation(p, 1u, seed);
  vec3 sumAll = vec3(0.0), sumB = vec3(0.0);
  uint keptAll = 0u, keptB = 0u;
  for (uint i = 0u; i < brdfa_pc.frame.w; ++i) {
    uint h = i & 1u;
    uvec4 u = brdfa_sample4D(h == 0u ? rotationA : rotationB, i >> 1u);
    float weight;
    vec3 l = brdfa_sampleCosineHemisphere(brdfa_unorm2(u.xy), weight);
    vec3 L = X * l.x + Y * l.y + N * l.z;
    vec3 c = BRDF(L, V, N, X, Y) * brdfa_environmentPreview(L) * weight;
    if (!brdfa_sampleKept(c)) continue;  // NaN or infinite (lib/shade_pixel.glsl)
    brdfa_addSample(c, h, sumAll, sumB, keptAll, keptB);
  }
  vec4 valueA, valueB;
  brdfa_halfValues(sumAll, sumB, keptAll, keptB, valueA, valueB);
  // Straight-line stores, no loop over the block (see above).
  if (c0) brdfa_storeHalves(i0, valueA, valueB);
  if (c1) brdfa_storeHalves(i1, valueA, valueB);
  if (c2) brdfa_storeHalves(i2, valueA, valueB);
  if (c3) brdfa_storeHalves(i3, valueA, valueB);
}
