// Importance sampling of the environment: directions in proportion to luminance
// times solid angle, from the alias table built by renderer/src/assets/environment_sampling.cpp.
// Both functions work in the environment's frame (lib/environment.glsl), as lookups do.
// A constant environment (the furnace) has no table: it is sampled uniformly over the sphere.

// Direction through (s, t) of cube face `face`, not normalised (its major component is +-1):
// the Vulkan cube convention, as cubeFaceDirection in renderer/src/assets/environment_maps.cpp:
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
  brdfa_envLog2D = brdfa_envEntry(0u).x;
  brdfa_envD = float(1u << brdfa_envLog2D);
#endif
}

#if !defined(BRDFA_ENV_CONSTANT)
// The cell holding unit direction `d`, and |d_major|. Total for any d, NaN included: the index
// is clamped into the table, so a user sampler's garbage direction never reads past it.
uint brdfa_environmentCell(vec3 d, out float major) {
  vec2 st;
  uint face = brdfa_cubeFaceCoords(d, st, major);
  uint last = (1u << brdfa_envLog2D) - 1u;
  // guard: s or t at exactly +1 (the face's far edge) would index one cell past the row.
  uvec2 cell = min(uvec2(max((st + 1.0) * (0.5 * brdfa_envD), vec2(0.0))), uvec2(last));
  return (((face << brdfa_envLog2D) + cell.y) << brdfa_envLog2D) + cell.x;
}

// The cell that 32 random bits pick uniformly: the first step of the alias method. All 32 bits
// count, so the pick is uniform over the cells to 1 part in 2^32 / cells.
uint brdfa_environmentPick(uint bits) {
  uint cell, unused;
  umulExtended(bits, 6u << (2u * brdfa_envLog2D), cell, unused);  // floor(bits * cells / 2^32)
  return cell;
}

// The second step: keep the picked cell when the top 13 random bits are below its threshold k
// (probability k / 8192), else take its alias (environment_sampling.h).
uint brdfa_environmentAliasStep(uint picked, uint bits) {
  uint word = brdfa_envEntry(1u + picked).x;
  return (bits >> 19u) < (word & 0x1fffu) ? picked : word >> 13u;
}

// A point drawn uniformly in (s, t) inside cell `cell`, as a unit direction, and its |d_major|.
// D is a power of two, so the cell index splits with shifts.
vec3 brdfa_environmentCellPoint(uint cell, uvec2 u, out float major) {
  uint last = (1u << brdfa_envLog2D) - 1u;
  uint face = cell >> (2u * brdfa_envLog2D);
  uvec2 c = uvec2(cell & last, (cell >> brdfa_envLog2D) & last);
  vec2 st = (vec2(c) + brdfa_unorm2(u)) * (2.0 / brdfa_envD) - 1.0;
  vec3 d = brdfa_cubeFacePoint(face, st);
  major = inversesqrt(dot(d, d));  // 1 / sqrt(1 + s^2 + t^2): d's major component is +-1
  return d * major;
}

// Density in solid angle of the draws at a direction in cell `cell` whose major component is
// `major`: density(cell) / |d_major|^3 (environment_sampling.h derives it).
float brdfa_environmentCellPdf(uint cell, float major) {
  return uintBitsToFloat(brdfa_envEntry(1u + cell).y) / (major * major * major);
}
#endif

// Density in solid angle of brdfa_sampleEnvironment's draws at unit direction `d`.
float brdfa_environmentPdf(vec3 d) {
#if defined(BRDFA_ENV_CONSTANT)
  return 1.0 / (4.0 * BRDFA_PI);
#else
  float major;
  uint cell = brdfa_environmentCell(d, major);
  return brdfa_environmentCellPdf(cell, major);
#endif
}

// Draws a unit direction from the environment's distribution and sets its solid-angle density:
// u.x picks a cell, u.y decides between it and its alias, u.zw place the point in the cell.
vec3 brdfa_sampleEnvironment(uvec4 u, out float pdf) {
#if defined(BRDFA_ENV_CONSTANT)
  float z = 1.0 - 2.0 * brdfa_unorm(u.x);
  float r = sqrt(max(0.0, 1.0 - z * z));  // guard: rounding can push 1 - z^2 below 0
  float phi = 2.0 * BRDFA_PI * brdfa_unorm(u.y);
  pdf = 1.0 / (4.0 * BRDFA_PI);
  return vec3(r * cos(phi), r * sin(phi), z);
#else
  uint cell = brdfa_environmentAliasStep(brdfa_environmentPick(u.x), u.y);
  float major;
  vec3 d = brdfa_environmentCellPoint(cell, u.zw, major);
  pdf = brdfa_environmentCellPdf(cell, major);
  return d;
#endif
}

// The environment's effective density (integral of pdf^2): how concentrated its light is.
float brdfa_environmentConcentration() {
#if defined(BRDFA_ENV_CONSTANT)
  return 1.0 / (4.0 * BRDFA_PI);
#else
  return uintBitsToFloat(brdfa_envEntry(0u).y);
#endif
}
