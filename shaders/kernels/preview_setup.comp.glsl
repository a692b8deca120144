// Stage 1 of 3 of the preview kernel (kernels/preview.comp.glsl says why it exists): everything
// of one sample that does not depend on the BRDF, at one pixel of each 2x2 block for a preview
// (target.w bit 1), else at every pixel for a first sample (RenderSettings::firstSampleKernel,
// over the exact environment: an estimate that counts as the image's sample 1). A fixed
// program, compiled once per environment kind, so a new BRDF's driver compile (lavapipe JITs
// at the first dispatch) leaves all this out: its frame, sample direction and coarse
// environment lookup alone took ~60 ms of that compile.
//
// Writes, per block, at brdfa_previewSlot() (lib/bindings.glsl):
//   +0 N, texCoord.x   +1 V, texCoord.y   +2 X, covered-pixel mask (bit k: pixel base + (k & 1, k >> 1))
//   +3 Y, the block's origin (x | y << 16)   +4 L   +5 L_env(L) * cos / pdf * intensity
// (float bits where a float). Mask 0: nothing of this object in the block; stages 2 and 3 skip it.
// The frame is always the tangent frame (BRDFA_TANGENT_FRAME): a BRDF that reads X and Y gets
// its program's frame, and for one that does not, any orthonormal frame serves the cosine
// sampling.

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

void main() {
  uint slot = brdfa_previewSlot();
  bool blocks = (brdfa_pc.target.w & 2u) != 0u;  // a preview; else a first sample per pixel
  // The block's pixels of this object, and the first of them, which is shaded (as a preview by
  // the program picks them, kernels/shade.comp.glsl); or this invocation's pixel (mask 1).
  uvec2 base, p, surface;
  uint mask;
  if (!brdfa_shadedPixel(blocks, base, mask, p, surface)) mask = 0u;
  brdfa_previewScratch[slot + 2u].w = mask;
  if (mask == 0u) return;
  vec3 N, V, X, Y;
  brdfa_surfaceFrame(p, surface, N, V, X, Y);
  brdfa_environmentBegin();
  // Sample 0 of half A, as a pass by the program takes it (kernels/shade.comp.glsl).
  uvec4 u = brdfa_sample4D(brdfa_halfRotation(p, 0u, brdfa_pc.target.y), 0u);
  float weight;
  vec3 l = brdfa_sampleCosineHemisphere(brdfa_unorm2(u.xy), weight);
  vec3 L = X * l.x + Y * l.y + N * l.z;
  // A first sample is the image's own estimate, so it reads the environment itself; a preview
  // reads the coarse one, less noisy for one sample per block.
  vec3 radiance = blocks ? brdfa_environmentPreview(L) : brdfa_environmentUnit(L);
  vec3 incoming = radiance * (weight * brdfa_environmentIntensity());
  brdfa_previewScratch[slot] = uvec4(floatBitsToUint(N), floatBitsToUint(texCoord.x));
  brdfa_previewScratch[slot + 1u] = uvec4(floatBitsToUint(V), floatBitsToUint(texCoord.y));
  brdfa_previewScratch[slot + 2u].xyz = floatBitsToUint(X);
  brdfa_previewScratch[slot + 3u] = uvec4(floatBitsToUint(Y), base.x | (base.y << 16u));
  brdfa_previewScratch[slot + 4u].xyz = floatBitsToUint(L);
  brdfa_previewScratch[slot + 5u].xyz = floatBitsToUint(incoming);
}
