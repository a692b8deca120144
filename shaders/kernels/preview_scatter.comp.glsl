// Stage 3 of 3 of the preview kernel (kernels/preview.comp.glsl): writes each block's value to
// the block's pixels this object covers (a first sample's mask is its one pixel), both halves
// overwritten (half A: the sample, half B: none), as a preview or first pass by the program
// would. A fixed program, so a new BRDF's driver compile
// leaves out these stores.

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

void main() {
  uint slot = brdfa_previewSlot();
  uint mask = brdfa_previewScratch[slot + 2u].w;
  if (mask == 0u) return;
  uint origin = brdfa_previewScratch[slot + 3u].w;
  // A preview overwrites (target.w), as lib/shade_pixel.glsl's write of a preview by the program.
  brdfa_writeShaded(uvec2(origin & 0xffffu, origin >> 16u), mask, true, uintBitsToFloat(brdfa_previewScratch[slot + 5u]),
                    vec4(0.0));
}
