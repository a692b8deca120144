// How the raster pass encodes the G-buffer (planes described in lib/bindings.glsl), shared by
// the fragment shader that writes it and the kernels that read it.

// Surface plane x: the object id in the low bits, this bit set where the tangent frame is
// left-handed (the mesh's tangent w < 0).
const uint BRDFA_LEFT_HANDED = 0x80000000u;
uint brdfa_objectId(uvec2 surface) { return surface.x & ~BRDFA_LEFT_HANDED; }

// Unit vectors in 32 bits: the octahedral map (Cigolle et al. 2014, "A Survey of Efficient
// Representations for Independent Unit Vectors", JCGT 3(2)), two 16-bit snorm coordinates.
// The worst angular error is about 1e-4 rad, far below a cubemap texel (2e-3 rad at 512 per
// face) and the G-buffer's own interpolation error.

vec2 brdfa_octWrap(vec2 v) {
  return (1.0 - abs(v.yx)) * vec2(v.x >= 0.0 ? 1.0 : -1.0, v.y >= 0.0 ? 1.0 : -1.0);
}

// n need not be unit; it must not be 0 (the caller marks a missing vector separately).
uint brdfa_octEncode(vec3 n) {
  n /= abs(n.x) + abs(n.y) + abs(n.z);
  return packSnorm2x16(n.z >= 0.0 ? n.xy : brdfa_octWrap(n.xy));
}

vec3 brdfa_octDecode(uint packed) {
  vec2 e = unpackSnorm2x16(packed);
  vec3 n = vec3(e, 1.0 - abs(e.x) - abs(e.y));
  // The lower hemisphere was folded over the diagonals: unfold it.
  float t = max(-n.z, 0.0);
  n.xy += vec2(n.x >= 0.0 ? -t : t, n.y >= 0.0 ? -t : t);
  return normalize(n);
}
