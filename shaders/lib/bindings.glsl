// Resources of one render view (descriptor set 0) and the per-dispatch push constants, shared
// by every compute kernel (shade, background, resolve). Names carry the brdfa_ prefix so they
// can never collide with names in a user's BRDF file.

// G-buffer, written once per camera/geometry change by the raster pass and copied into this
// buffer (storage-buffer loads are far cheaper than storage-image loads on CPU devices).
// Three planes of width*height texels each:
//   0 position: xyz world position, w = object id (1-based) * tangent handedness; 0 = background
//   1 normal:   xyz world shading normal (faces the camera), w = texCoord.x
//   2 tangent:  xyz world tangent, w = texCoord.y
layout(std430, set = 0, binding = 0) readonly buffer BrdfaGbuffer { vec4 brdfa_gbuffer[]; };

// Two half accumulators (sample i of a pixel goes to half i & 1, each half with its own random
// sequence): rgb = sum of radiance samples, a = number of samples kept. The difference of
// their means estimates the error of the combined mean.
layout(std430, set = 0, binding = 3) buffer BrdfaAccum { vec4 brdfa_accum[]; };
layout(std430, set = 0, binding = 4) buffer BrdfaCounters { uint brdfa_nanSamples; uint brdfa_counterPad[3]; };
layout(set = 0, binding = 5) uniform samplerCube brdfa_envMap;
layout(std430, set = 0, binding = 6) writeonly buffer BrdfaOutRgba8 { uint brdfa_outRgba8[]; };
layout(std430, set = 0, binding = 7) writeonly buffer BrdfaOutFloat { vec4 brdfa_outFloat[]; };
layout(std430, set = 0, binding = 8) writeonly buffer BrdfaPartials { vec4 brdfa_partials[]; };
// The environment's importance-sampling table (renderer/src/assets/environment_sampling.h), a texel
// buffer of RG32UI entries: entry 0 (log2 D, effective density as float bits), then per cell
// (alias << 13 | keep threshold, density as float bits). A constant environment binds the
// header alone.
layout(set = 0, binding = 9) uniform usamplerBuffer brdfa_envTable;
uvec2 brdfa_envEntry(uint i) { return texelFetch(brdfa_envTable, int(i)).xy; }

layout(push_constant) uniform BrdfaPush {
  vec4 cameraPos;      // xyz
  vec4 cameraRight;    // xyz, scaled by tan(fov/2) * aspect
  vec4 cameraUp;       // xyz, scaled by tan(fov/2)
  vec4 cameraForward;  // xyz, unit
  vec4 env;            // x intensity, y cos(rotation), z sin(rotation)
  uvec4 frame;         // x width, y height, z index of this pass's first sample, w samples this pass
  uvec4 target;        // x object id (1-based), y render.seed,
                       // z shade: dispatch origin x | y << 16; resolve: write float output,
                       // w first pass after a restart (overwrite instead of add)
  vec4 tone;           // x exposure scale 2^exposure, y tone map (0 clamp, 1 reinhard, 2 aces)
} brdfa_pc;

uint brdfa_pixelIndex(uvec2 p) { return p.y * brdfa_pc.frame.x + p.x; }
uint brdfa_planeSize() { return brdfa_pc.frame.x * brdfa_pc.frame.y; }
uint brdfa_halfOffset(uint halfIndex) { return halfIndex * brdfa_planeSize(); }
vec4 brdfa_gPosition(uint i) { return brdfa_gbuffer[i]; }
vec4 brdfa_gNormal(uint i) { return brdfa_gbuffer[brdfa_planeSize() + i]; }
vec4 brdfa_gTangent(uint i) { return brdfa_gbuffer[2u * brdfa_planeSize() + i]; }
