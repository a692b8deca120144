// Importance sampling of the environment (issue 11): directions in proportion to luminance
// times solid angle, from the alias table built by renderer/src/environment_sampling.cpp.
// Both functions work in the environment's frame (lib/environment.glsl), as lookups do.
// A constant environment (the furnace) has no table: it is sampled uniformly over the sphere.

// Direction through (s, t) of cube face `face`, not normalised (its major component is +-1):
// the Vulkan cube convention, as cubeFaceDirection in renderer/src/environment_maps.cpp:
//   +X (1, -t, -s)  -X (-1, -t, s)  +Y (s, 1, t)  -Y (s, -1, -t)  +Z (s, -t, 1)  -Z (-s, -t, -1).
// Written with selects, not branches: a CPU device runs every branch of divergent code for all
// its SIMD lanes, and neighbouring lanes draw from different faces.
vec3 brdfa_cubeFacePoint(uint face, vec2 st) {
  uint axis = face >> 1u;
  float sgn = (face & 1u) == 0u ? 1.0 : -1.0;
  vec3 onX = vec3(sgn, -st.y, -sgn * st.x);
  vec3 onY = vec3(st.x, sgn, sgn * st.y);
  vec3 onZ = vec3(sgn * st.x, -st.y, sgn);
  return axis == 0u ? onX : (axis == 1u ? onY : onZ);
}

// The face holding unit direction `d`, the point (s, t) where d meets it, and |d_major|: the
// inverse of brdfa_cubeFacePoint (cubeFaceCoords in environment_maps.cpp), with selects too.
uint brdfa_cubeFaceCoords(vec3 d, out vec2 st, out float major) {
  vec3 a = abs(d);
  bool onX = a.x >= a.y && a.x >= a.z;
  bool onY = !onX && a.y >= a.z;
  uint axis = onX ? 0u : (onY ? 1u : 2u);
  float m = onX ? d.x : (onY ? d.y : d.z);  // the major component, signed
  float sgn = m >= 0.0 ? 1.0 : -1.0;
  vec2 sc = onX ? vec2(-sgn * d.z, -d.y) : (onY ? vec2(d.x, sgn * d.z) : vec2(sgn * d.x, -d.y));
  major = abs(m);
  st = sc / major;
  return 2u * axis + (m >= 0.0 ? 0u : 1u);
}

// The table's header, read once per pixel (brdfa_environmentBegin) instead of once per sample.
uint brdfa_envLog2D = 0u;  // log2 of cells per face edge
float brdfa_envD = 0.0;    // cells per face edge

void brdfa_environmentBegin() {
#if !defined(BRDFA_ENV_CONSTANT)
  vec4 header = brdfa_envEntry(0u);
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
  return brdfa_envEntry(1u + index).z / (major * major * major);
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
  vec4 e = brdfa_envEntry(1u + cell);
  float density = e.z;
  if (brdfa_unorm(u.y) >= e.x) {
    cell = uint(e.y);
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
  return brdfa_envEntry(0u).y;
#endif
}
