// The environment as the preview kernel (kernels/preview.comp.glsl) sees it: the cube averaged
// over 6 x P x P cells (P = 2^BRDFA_PREVIEW_LOG2_CELLS), nearest cell, in entries of the
// environment's table after its sampling cells (renderer/src/assets/environment_preview.h):
// per cell (packHalf2x16(r, g), packHalf2x16(b, 0)) of the radiance / the cube's scale, like
// the cube's texels. A table read instead of a filtered cube lookup: on a CPU device (lavapipe)
// the cube's sampling code alone is ~80 ms of a new program's driver compile.
// Needs brdfa_environmentBegin() (the table's header).

vec3 brdfa_environmentPreview(vec3 envDir) {
#if defined(BRDFA_ENV_CONSTANT)
  return vec3(1.0);
#else
  const uint log2P = uint(BRDFA_PREVIEW_LOG2_CELLS);
  vec2 st;
  float major;
  uint face = brdfa_cubeFaceCoords(envDir, st, major);
  // guard: s or t at exactly +1 (the face's far edge) would index one cell past the row, and a
  // NaN direction (a user's garbage) must still read inside the table.
  uvec2 cell = min(uvec2(max((st + 1.0) * float(1u << (log2P - 1u)), vec2(0.0))), uvec2((1u << log2P) - 1u));
  uint first = 1u + (6u << (2u * brdfa_envLog2D));  // after the header and the sampling cells
  uvec2 e = brdfa_envEntry(first + (((face << log2P) + cell.y) << log2P) + cell.x);
  return vec3(unpackHalf2x16(e.x), unpackHalf2x16(e.y).x);
#endif
}
