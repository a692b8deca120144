// The environment seen directly, for pixels the raster pass left empty. It is deterministic,
// so it runs once per accumulation restart and writes radiance L with weight 1 into both half
// accumulators: the resolved mean is L, whatever the object pixels' sample counts.
layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

void main() {
  uvec2 p = gl_GlobalInvocationID.xy;
  if (p.x >= brdfa_pc.frame.x || p.y >= brdfa_pc.frame.y) return;
  uint pixel = brdfa_pixelIndex(p);
  if (brdfa_gPosition(pixel).w != 0.0) return;  // covered by an object

  vec2 ndc = vec2(2.0 * (float(p.x) + 0.5) / float(brdfa_pc.frame.x) - 1.0,
                  1.0 - 2.0 * (float(p.y) + 0.5) / float(brdfa_pc.frame.y));  // row 0 is the top
  vec3 dir = normalize(brdfa_pc.cameraForward.xyz + ndc.x * brdfa_pc.cameraRight.xyz +
                       ndc.y * brdfa_pc.cameraUp.xyz);
  vec4 value = vec4(brdfa_environmentUnit(brdfa_toEnvironment(dir)) * brdfa_environmentIntensity(), 1.0);
  brdfa_accum[pixel] = value;
  brdfa_accum[brdfa_halfOffset(1u) + pixel] = value;
}
