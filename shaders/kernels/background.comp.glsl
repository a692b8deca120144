// The environment seen directly, for pixels the raster pass left empty. Two uses:
//  - once per accumulation restart (frame.w = 0), over the whole image and G-buffer slice 0:
//    radiance L with weight 1 into both half accumulators, so the resolved mean is L whatever
//    the object pixels' sample counts (it is deterministic: no need to redo it every pass);
//  - every pass with anti-aliasing (frame.w = samples this pass, frame.z the first one's index),
//    over the objects' screen bounds and that pass's slice: where this slice sees no object,
//    frame.w samples of L are added (or written, on the first pass) to the halves like the
//    shade kernel's, so an edge pixel ends up the
//    average over its sub-pixel positions. This overrides the once-per-restart value there.
// The view ray passes through pixel centre + (tone.z, tone.w) pixels, as the raster pass did.
layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

void main() {
  uvec2 p = gl_GlobalInvocationID.xy + uvec2(brdfa_pc.target.z & 0xffffu, brdfa_pc.target.z >> 16);
  if (p.x >= brdfa_pc.frame.x || p.y >= brdfa_pc.frame.y) return;
  uint pixel = brdfa_pixelIndex(p);
  if (brdfa_gPosition(pixel).w != 0.0) return;  // covered by an object

  vec2 at = vec2(p) + 0.5 + brdfa_pc.tone.zw;
  vec2 ndc = vec2(2.0 * at.x / float(brdfa_pc.frame.x) - 1.0,
                  1.0 - 2.0 * at.y / float(brdfa_pc.frame.y));  // row 0 is the top
  vec3 dir = normalize(brdfa_pc.cameraForward.xyz + ndc.x * brdfa_pc.cameraRight.xyz +
                       ndc.y * brdfa_pc.cameraUp.xyz);
  vec3 radiance = brdfa_environmentUnit(brdfa_toEnvironment(dir)) * brdfa_environmentIntensity();
  uint count = brdfa_pc.frame.w;
  if (count == 0u) {
    brdfa_accum[pixel] = vec4(radiance, 1.0);
    brdfa_accum[brdfa_halfOffset(1u) + pixel] = vec4(radiance, 1.0);
    return;
  }
  // The pass's samples first .. first + count - 1 go to the halves by parity, as in the shade
  // kernel: half A takes the even indices.
  uint first = brdfa_pc.frame.z;
  float countA = float((first + count + 1u) / 2u - (first + 1u) / 2u);
  float countB = float(count) - countA;
  vec4 valueA = vec4(radiance * countA, countA);
  vec4 valueB = vec4(radiance * countB, countB);
  if (brdfa_pc.target.w != 0u) {
    brdfa_accum[pixel] = valueA;
    brdfa_accum[brdfa_halfOffset(1u) + pixel] = valueB;
  } else {
    brdfa_accum[pixel] += valueA;
    brdfa_accum[brdfa_halfOffset(1u) + pixel] += valueB;
  }
}
