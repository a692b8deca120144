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

// --- Four dimensions per sample, two independent replicates.
//
// Sample i of a pixel goes to half accumulator i & 1 as point j = i >> 1 of that half's own
// sequence, shifted by that half's own random rotation: the two halves are statistically
// independent randomised-QMC estimates, so the difference of their means measures the error of
// the combined mean (resolve), and no pass partition changes which sample a half gets.
// .xy is the R2 point j (the best 2D lattice for the hemisphere samplers and the environment's
// cell and alias choice); .zw is the same R2 point with an independent random shift (the
// position inside an environment cell). Each point is uniform in [0,1)^4 with independent
// coordinates, because every shift is independent and uniform: the estimate stays unbiased.
uvec4 brdfa_halfRotation(uvec2 pixel, uint halfIndex, uint seed) {
  uint h = brdfa_hash(pixel.x ^ brdfa_hash(pixel.y + 0x9e3779b9u) ^ brdfa_hash(halfIndex * 0x632be5abu + seed));
  uint h1 = brdfa_hash(h ^ 0x85ebca6bu);
  uint h2 = brdfa_hash(h1 ^ 0xc2b2ae35u);
  uint h3 = brdfa_hash(h2 ^ 0x27d4eb2fu);
  return uvec4(h, h1, h2, h3);
}

// Point j of the rotated sequences: four uniform 32-bit values.
uvec4 brdfa_sample4D(uvec4 rotation, uint j) {
  uvec2 r2 = j * uvec2(3242174889u, 2447445414u);  // round(2^32 / g), round(2^32 / g^2), as above
  return rotation + uvec4(r2, r2);
}

// A 32-bit uniform value as a float in [0, 1): 24 bits, exact, never 1.
float brdfa_unorm(uint u) { return float(u >> 8u) * (1.0 / 16777216.0); }
vec2 brdfa_unorm2(uvec2 u) { return vec2(u >> 8u) * (1.0 / 16777216.0); }
