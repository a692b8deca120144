// Resolves the two half accumulators into the displayed frame and, per subgroup, the partial
// sums of the error estimate (subgroup adds: no shared memory and no barriers, which are
// expensive on CPU devices). Needs GL_KHR_shader_subgroup_arithmetic, enabled by the host.
//
// Per pixel, with half means mA, mB over nA, nB samples: E[(mA - mB)^2] = s^2 (1/nA + 1/nB),
// so the variance of the combined mean (over nA + nB samples) is estimated by
//   (mA - mB)^2 / ((1/nA + 1/nB) (nA + nB)).
// The host reports rel_error = sqrt(mean variance) / mean luminance over object pixels.
layout(local_size_x = 16, local_size_y = 16, local_size_z = 1) in;

void main() {
  uvec2 p = gl_GlobalInvocationID.xy;
  vec3 partial = vec3(0.0);  // (variance, luminance, pixel count)
  if (p.x < brdfa_pc.frame.x && p.y < brdfa_pc.frame.y) {
    uint i = brdfa_pixelIndex(p);
    vec4 a = brdfa_accumLoad(0u, i);
    vec4 b = brdfa_accumLoad(1u, i);
    float n = a.w + b.w;
    vec3 mean = n > 0.0 ? (a.rgb + b.rgb) / n : vec3(0.0);  // guard: no samples yet
    brdfa_outRgba8[i] = brdfa_packSrgb8(mean, brdfa_pc.tone.x, brdfa_pc.tone.y);  // exposure, tone map
    if (brdfa_pc.target.z != 0u) brdfa_outFloat[i] = vec4(mean, 1.0);
    bool objectPixel = brdfa_gSurface(i).x != 0u;
    if (objectPixel && a.w > 0.0 && b.w > 0.0) {
      float d = brdfa_luminance(a.rgb / a.w) - brdfa_luminance(b.rgb / b.w);
      float variance = d * d / ((1.0 / a.w + 1.0 / b.w) * n);
      partial = vec3(variance, brdfa_luminance(mean), 1.0);
    }
  }
  vec3 total = subgroupAdd(partial);
  if (subgroupElect()) {
    uint group = gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x;
    brdfa_partials[group * gl_NumSubgroups + gl_SubgroupID] = vec4(total, 0.0);
  }
}
