// Resources of one render view (descriptor set 0) and the per-dispatch push constants, shared
// by every compute kernel (shade, background, resolve). Names carry the brdfa_ prefix so they
// can never collide with names in a user's BRDF file.

// Binding 0 is a plain storage buffer for the analysis and check kernels, which pass their
// inputs through it; render views bind the G-buffer there and read it through the texel views
// below. The accumulators (binding 3) are a storage buffer in every kernel: on lavapipe an
// image store to a storage texel buffer cost ~6 ms more per 2 x 512^2 stores, and a 1-sample
// pass of the GGX sphere took 30 ms with the accumulators as a texel buffer against 22 ms as
// a storage buffer (bench --only shaders, interleaved).
layout(std430, set = 0, binding = 0) readonly buffer BrdfaGbuffer { vec4 brdfa_gbuffer[]; };

// Two half accumulators (sample i of a pixel goes to half i & 1, each half with its own random
// sequence): rgb = sum of radiance samples, a = number of samples kept. The difference of
// their means estimates the error of the combined mean. Entry i is half A of pixel i, entry
// planeSize + i its half B (brdfa_accumLoad, brdfa_accumStore below).
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

// The G-buffer of this pass's sub-pixel slice, written once per camera or geometry change by
// the raster pass (kernels/gbuffer.frag.glsl) and copied into two planes:
//  - surface (binding 10), RG32UI: x = object id (1-based), | 0x80000000 where the tangent
//    frame is left-handed, 0 = background; y = the shading normal (world space, facing the
//    camera), octahedral (lib/gbuffer_encoding.glsl);
//  - detail (binding 11), RGBA32UI: x = the tangent (world space, octahedral), y, z = texCoord
//    (float bits), w = 1 where the mesh has no usable tangent. Read only by programs whose BRDF
//    uses the tangent frame or texCoord.
// The view direction is not stored: the surface point lies on the pixel's view ray
// (brdfa_viewRay), which gives V exactly.
layout(set = 0, binding = 10) uniform usamplerBuffer brdfa_gSurfaceTexels;
layout(set = 0, binding = 11) uniform usamplerBuffer brdfa_gDetailTexels;
// Pixels whose coverage differs between the G-buffer slices (an object in some, background in
// others), R32UI pixel indices: the edge kernel's work list once every slice is known (CPU
// devices).
layout(set = 0, binding = 13) uniform usamplerBuffer brdfa_edgePixels;
// The preview's hand-over between its three stages (kernels/preview_setup, preview,
// preview_scatter .comp.glsl): BRDFA_PREVIEW_STRIDE texels per 2x2 block of one dispatch, in
// invocation order (brdfa_previewSlot). Words, so the bits of a block origin or mask pass
// through unchanged.
layout(std430, set = 0, binding = 12) buffer BrdfaPreviewScratch { uvec4 brdfa_previewScratch[]; };

layout(push_constant) uniform BrdfaPush {
  vec4 cameraPos;      // xyz; w (shade, as uint bits): rows | step << 16 of the dispatch's band
  vec4 cameraRight;    // xyz, scaled by tan(fov/2) * aspect
  vec4 cameraUp;       // xyz, scaled by tan(fov/2)
  vec4 cameraForward;  // xyz, unit
  vec4 env;            // x intensity, y cos(rotation), z sin(rotation)
  uvec4 frame;         // x width, y height, z index of this pass's first sample, w samples this pass
  uvec4 target;        // x object id (1-based), y render.seed,
                       // z shade: dispatch origin x | y << 16; resolve: write float output,
                       // w first pass after a restart (overwrite instead of add)
  vec4 tone;           // x exposure scale 2^exposure, y tone map (0 clamp, 1 reinhard, 2 aces),
                       // zw the slice's sub-pixel offset (shade, background)
} brdfa_pc;

uint brdfa_pixelIndex(uvec2 p) { return p.y * brdfa_pc.frame.x + p.x; }
uint brdfa_planeSize() { return brdfa_pc.frame.x * brdfa_pc.frame.y; }
uint brdfa_halfOffset(uint halfIndex) { return halfIndex * brdfa_planeSize(); }
uvec2 brdfa_gSurface(uint i) { return texelFetch(brdfa_gSurfaceTexels, int(i)).xy; }
uvec4 brdfa_gDetail(uint i) { return texelFetch(brdfa_gDetailTexels, int(i)); }
vec4 brdfa_accumLoad(uint halfIndex, uint pixel) { return brdfa_accum[brdfa_halfOffset(halfIndex) + pixel]; }
void brdfa_accumStore(uint halfIndex, uint pixel, vec4 value) { brdfa_accum[brdfa_halfOffset(halfIndex) + pixel] = value; }
// The preview scratch's first texel for this invocation: the three stages dispatch the same grid
// of 8x8 workgroups. (Not gl_WorkGroupSize: this file comes before the kernel's local_size.)
const uint BRDFA_PREVIEW_STRIDE = 6u;
uint brdfa_previewSlot() {
  return (gl_GlobalInvocationID.y * gl_NumWorkGroups.x * 8u + gl_GlobalInvocationID.x) * BRDFA_PREVIEW_STRIDE;
}
// Adds `value` to a half's texel, or overwrites it on the first pass after a restart (so a
// change of BRDF or parameters needs no clear of the whole buffer).
void brdfa_accumulate(uint halfIndex, uint pixel, vec4 value, bool overwrite) {
  if (!overwrite) value += brdfa_accumLoad(halfIndex, pixel);
  brdfa_accumStore(halfIndex, pixel, value);
}

// Unit direction of the view ray through pixel p at sub-pixel offset `jitter` (pixels), as the
// raster pass sampled that slice: row 0 is the top of the image.
vec3 brdfa_viewRay(uvec2 p, vec2 jitter) {
  vec2 at = vec2(p) + 0.5 + jitter;
  vec2 ndc = vec2(2.0 * at.x / float(brdfa_pc.frame.x) - 1.0, 1.0 - 2.0 * at.y / float(brdfa_pc.frame.y));
  return normalize(brdfa_pc.cameraForward.xyz + ndc.x * brdfa_pc.cameraRight.xyz + ndc.y * brdfa_pc.cameraUp.xyz);
}
