// The environment seen directly, for pixels the raster pass left empty. Two uses:
//  - once per accumulation restart (frame.w = 0), over the whole image and G-buffer slice 0:
//    radiance L with weight 1 into both half accumulators, so the resolved mean is L whatever
//    the object pixels' sample counts (it is deterministic: no need to redo it every pass);
//  - every pass with anti-aliasing (frame.w = samples this pass, frame.z the first one's index),
//    over the objects' screen bounds, or the list of edge pixels once it is known, and that
//    pass's slice: where this slice sees no object,
//    frame.w samples of L are added (or written, on the first pass) to the halves like the
//    shade kernel's, so an edge pixel ends up the
//    average over its sub-pixel positions. This overrides the once-per-restart value there.
// The view ray passes through pixel centre + (tone.z, tone.w) pixels, as the raster pass did.
layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

void main() {
  // target.w bit 1: a preview's once-per-restart write, one lookup per 2x2 block through the
  // block's centre, written to the block's pixels the raster left empty (local_view.cpp,
  // recordPending); the next pass writes the full-resolution background.
  bool blocks = (brdfa_pc.target.w & 2u) != 0u;
  uvec2 p;
  if (brdfa_pc.target.x != 0u) {
    // The per-pass use over a list of target.x edge pixels (brdfa_edgePixels), 64 per group,
    // covered in some slices only: a pixel no slice covers already holds the background
    // averaged over the first four passes' sub-pixel positions (one per slice, weighted by
    // their sample counts), an estimate as good as more of the same would give. (A CPU device
    // runs the kernel's code for every pixel dispatched, hit or not: over the bounds, ~10 ms
    // a pass at 512^2.)
    uint k = gl_WorkGroupID.x * 64u + gl_LocalInvocationIndex;
    if (k >= brdfa_pc.target.x) return;
    uint listed = texelFetch(brdfa_edgePixels, int(k)).x;
    p = uvec2(listed % brdfa_pc.frame.x, listed / brdfa_pc.frame.x);
  } else {
    p = (blocks ? 2u : 1u) * gl_GlobalInvocationID.xy + uvec2(brdfa_pc.target.z & 0xffffu, brdfa_pc.target.z >> 16);
    if (p.x >= brdfa_pc.frame.x || p.y >= brdfa_pc.frame.y) return;
  }
  uint pixel = brdfa_pixelIndex(p);
  if (!blocks && brdfa_gSurface(pixel).x != 0u) return;  // covered by an object

  vec2 at = brdfa_pc.tone.zw + (blocks ? vec2(0.5) : vec2(0.0));
  vec3 radiance = brdfa_environmentUnit(brdfa_toEnvironment(brdfa_viewRay(p, at))) * brdfa_environmentIntensity();
  uint count = brdfa_pc.frame.w;
  if (count == 0u) {
    // A loop, not an if: a CPU device skips a loop no lane enters (the full-resolution write's
    // three other pixels), but runs both sides of an if for every lane.
    for (uint k = 0u; k < (blocks ? 4u : 1u); ++k) {
      uvec2 q = p + uvec2(k & 1u, k >> 1u);
      if (q.x >= brdfa_pc.frame.x || q.y >= brdfa_pc.frame.y) continue;
      uint written = brdfa_pixelIndex(q);
      if (blocks && brdfa_gSurface(written).x != 0u) continue;
      brdfa_accumStore(0u, written, vec4(radiance, 1.0));
      brdfa_accumStore(1u, written, vec4(radiance, 1.0));
    }
    return;
  }
  // The pass's samples first .. first + count - 1 go to the halves by parity, as in the shade
  // kernel: half A takes the even indices.
  uint first = brdfa_pc.frame.z;
  float countA = float((first + count + 1u) / 2u - (first + 1u) / 2u);
  float countB = float(count) - countA;
  bool overwrite = (brdfa_pc.target.w & 1u) != 0u;
  brdfa_accumulate(0u, pixel, vec4(radiance * countA, countA), overwrite);
  brdfa_accumulate(1u, pixel, vec4(radiance * countB, countB), overwrite);
}
