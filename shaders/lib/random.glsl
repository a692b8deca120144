// Sample generation: a low-discrepancy 2D sequence that continues across progressive passes.
//
// R2 sequence (M. Roberts 2018, "The unreasonable effectiveness of quasirandom sequences"):
// x_i = frac(i * (1/g, 1/g^2)), g the plastic number. Computed in 0.32 fixed point so the
// index can grow to 2^32 without losing precision (float frac(i*a) loses all bits past ~2^20).
// Each pixel gets a random Cranley-Patterson rotation (a toroidal shift), which makes every
// sample uniformly distributed, so the estimator stays unbiased, and decorrelates pixels.

// Integer hash "lowbias32" (C. Wellons, 2018): good avalanche for 5 operations.
uint brdfa_hash(uint x) {
  x ^= x >> 16;
  x *= 0x7feb352du;
  x ^= x >> 15;
  x *= 0x846ca68bu;
  x ^= x >> 16;
  return x;
}

uvec2 brdfa_pixelRotation(uvec2 pixel) {
  uint h = brdfa_hash(pixel.x ^ brdfa_hash(pixel.y + 0x9e3779b9u));
  return uvec2(h, brdfa_hash(h ^ 0x85ebca6bu));
}

// The i-th point of the rotated R2 sequence in [0,1)^2, with 24 bits per coordinate so the
// float conversion is exact and 1.0 is never returned.
vec2 brdfa_sample2D(uvec2 rotation, uint i) {
  uvec2 r = rotation + i * uvec2(3242174889u, 2447445414u);  // round(2^32 / g), round(2^32 / g^2)
  return vec2(r >> 8u) * (1.0 / 16777216.0);
}
