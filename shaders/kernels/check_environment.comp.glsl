// Draws of the environment sampler for Renderer::checkEnvironmentSampler. Invocation
// k draws one direction from independent pseudo-random numbers (a chi-square test needs
// independent draws, not a low-discrepancy sequence) and writes
//   out[2k] = (direction, the pdf the sampler returned), out[2k + 1] = (brdfa_environmentPdf
//   of that direction, 0, 0, 0).
layout(local_size_x = 8, local_size_y = 1, local_size_z = 1) in;

void main() {
  uint k = gl_GlobalInvocationID.x;
  if (2u * k + 1u >= uint(brdfa_accum.length())) return;
  uint h0 = brdfa_hash(brdfa_hash(k) ^ 0x3c6ef372u);
  uint h1 = brdfa_hash(h0 ^ 0xa54ff53au);
  uint h2 = brdfa_hash(h1 ^ 0x510e527fu);
  uint h3 = brdfa_hash(h2 ^ 0x9b05688cu);
  brdfa_environmentBegin();
  float pdf;
  vec3 d = brdfa_sampleEnvironment(uvec4(h0, h1, h2, h3), pdf);
  brdfa_accum[2u * k] = vec4(d, pdf);
  brdfa_accum[2u * k + 1u] = vec4(brdfa_environmentPdf(d), 0.0, 0.0, 0.0);
}
