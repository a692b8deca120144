// Importance sampling of the environment (issue 11): directions in proportion to luminance
// times solid angle, from the alias table built by renderer/src/environment_sampling.cpp.
// Both functions work in the environment's frame (lib/environment.glsl), as lookups do.
// A constant environment (the furnace) has no table: it is sampled uniformly over the sphere.

// Direction through (s, t) of cube face `face`, not normalised (its major component is +-1):
// the Vulkan cube convention, as cubeFaceDirection in renderer/src/environment_maps.cpp.
vec3 brdfa_cubeFacePoint(uint face, vec2 st) {
  if (face == 0u) return vec3(1.0, -st.y, -st.x);
  if (face == 1u) return vec3(-1.0, -st.y, st.x);
  if (face == 2u) return vec3(st.x, 1.0, st.y);
  if (face == 3u) return vec3(st.x, -1.0, -st.y);
  if (face == 4u) return vec3(st.x, -st.y, 1.0);
  return vec3(-st.x, -st.y, -1.0);
}

// The face holding unit direction `d`, the point (s, t) where d meets it, and |d_major|: the
// inverse of brdfa_cubeFacePoint (cubeFaceCoords in environment_maps.cpp).
uint brdfa_cubeFaceCoords(vec3 d, out vec2 st, out float major) {
  vec3 a = abs(d);
  uint face;
  vec2 sc;
  if (a.x >= a.y && a.x >= a.z) {
    face = d.x >= 0.0 ? 0u : 1u;
    sc = vec2(d.x >= 0.0 ? -d.z : d.z, -d.y);
    major = a.x;
  } else if (a.y >= a.z) {
    face = d.y >= 0.0 ? 2u : 3u;
    sc = vec2(d.x, d.y >= 0.0 ? d.z : -d.z);
    major = a.y;
  } else {
    face = d.z >= 0.0 ? 4u : 5u;
    sc = vec2(d.z >= 0.0 ? d.x : -d.x, -d.y);
    major = a.z;
  }
  st = sc / major;
  return face;
}

// The table's header, read once per pixel (brdfa_environmentBegin) instead of once per sample.
uint brdfa_envLog2D = 0u;  // log2 of cells per face edge
float brdfa_envD = 0.0;    // cells per face edge

void brdfa_environmentBegin() {
#if !defined(BRDFA_ENV_CONSTANT)
  vec4 header = brdfa_envTable[0];
  brdfa_envD = header.x;
  brdfa_envLog2D = uint(header.z);
#endif
}

// Density in solid angle of brdfa_sampleEnvironment's draws at unit direction `d`:
// density(cell) / |d_major|^3 (environment_sampling.h derives it).
float brdfa_environmentPdf(vec3 d) {
#if defined(BRDFA_ENV_CONSTANT)
  return 1.0 / (4.0 * BRDFA_PI);
#else
  vec2 st;
  float major;
  uint face = brdfa_cubeFaceCoords(d, st, major);
  uint last = (1u << brdfa_envLog2D) - 1u;
  // guard: s or t at exactly +1 (the face's far edge) would index one cell past the row.
  uvec2 cell = min(uvec2(max((st + 1.0) * (0.5 * brdfa_envD), vec2(0.0))), uvec2(last));
  uint index = (((face << brdfa_envLog2D) + cell.y) << brdfa_envLog2D) + cell.x;
  return brdfa_envTable[1u + index].z / (major * major * major);
#endif
}

// Draws a unit direction from the environment's distribution and sets its solid-angle density.
// u.x picks a cell (all 32 bits: the pick is uniform over the cells to 1 part in 2^32 / cells),
// u.y decides between the cell and its alias, u.zw place the point in the cell uniformly in
// (s, t). D is a power of two, so the cell index splits with shifts.
vec3 brdfa_sampleEnvironment(uvec4 u, out float pdf) {
#if defined(BRDFA_ENV_CONSTANT)
  float z = 1.0 - 2.0 * brdfa_unorm(u.x);
  float r = sqrt(max(0.0, 1.0 - z * z));  // guard: rounding can push 1 - z^2 below 0
  float phi = 2.0 * BRDFA_PI * brdfa_unorm(u.y);
  pdf = 1.0 / (4.0 * BRDFA_PI);
  return vec3(r * cos(phi), r * sin(phi), z);
#else
  uint cell, unused;
  umulExtended(u.x, 6u << (2u * brdfa_envLog2D), cell, unused);  // floor(u.x * cells / 2^32)
  vec4 e = brdfa_envTable[1u + cell];
  float density = e.z;
  if (brdfa_unorm(u.y) >= e.x) {
    cell = floatBitsToUint(e.y);
    density = e.w;
  }
  uint last = (1u << brdfa_envLog2D) - 1u;
  uint face = cell >> (2u * brdfa_envLog2D);
  uvec2 c = uvec2(cell & last, (cell >> brdfa_envLog2D) & last);
  vec2 st = (vec2(c) + brdfa_unorm2(u.zw)) * (2.0 / brdfa_envD) - 1.0;
  vec3 d = brdfa_cubeFacePoint(face, st);
  float r2 = dot(d, d);  // 1 + s^2 + t^2 >= 1
  pdf = density * r2 * sqrt(r2);
  return d * inversesqrt(r2);
#endif
}

// The environment's effective density (integral of pdf^2): how concentrated its light is.
float brdfa_environmentConcentration() {
#if defined(BRDFA_ENV_CONSTANT)
  return 1.0 / (4.0 * BRDFA_PI);
#else
  return brdfa_envTable[0].y;
#endif
}
