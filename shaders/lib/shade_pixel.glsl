// Where one invocation of a shading dispatch (kernels/shade.comp.glsl, kernels/preview.comp.glsl)
// shades, and where its result goes: the first and last steps both kernels share.

// The dispatch covers a band of 8x8 tiles of the object's screen bounds, starting at the
// packed origin (target.z); workgroup row y shades the band's tile row (y * step) mod rows, so
// that the CPU device's threads each get rows from all over the band (local_view.cpp,
// renderPass). Returns this invocation's pixel, `scale` pixels apart (2: a preview's blocks).
uvec2 brdfa_dispatchPixel(uint scale) {
  uint permutation = floatBitsToUint(brdfa_pc.cameraPos.w);
  // (y * step) mod rows through a float quotient, exact for products below 2^24 (bands of at
  // most 512 rows): a CPU device divides integers one lane at a time.
  uint rows = permutation & 0xffffu, product = gl_WorkGroupID.y * (permutation >> 16);
  uint tileRow = product - rows * uint(float(product) / float(rows));
  return scale * uvec2(gl_GlobalInvocationID.x, tileRow * 8u + gl_LocalInvocationID.y) +
         uvec2(brdfa_pc.target.z & 0xffffu, brdfa_pc.target.z >> 16);
}

// For kernels/shade.comp.glsl: a pass shades pixel brdfa_dispatchPixel(1); a `preview` (target.w
// bit 1, RenderSettings::previewPass) one pixel of each 2x2 block: invocation q stands for the
// block at origin + 2q, and its value goes to every pixel of the block this object covers (the
// next pass overwrites it).
// Returns false where this invocation has nothing of the object to shade. Else `base` is its
// pixel (or block origin), bit k of `blockMask` marks pixel base + (k & 1, k >> 1) as the
// object's (bit 0 alone outside a preview), `p` is the pixel to shade and `surface` its
// G-buffer surface texel.
bool brdfa_shadedPixel(bool preview, out uvec2 base, out uint blockMask, out uvec2 p, out uvec2 surface) {
  base = brdfa_dispatchPixel(preview ? 2u : 1u);
  blockMask = 0u;
  p = base;
  surface = uvec2(0u);
  if (base.x >= brdfa_pc.frame.x || base.y >= brdfa_pc.frame.y) return false;
  // A loop, not an if: a CPU device skips a loop no lane enters, but runs both sides of an if
  // for every lane.
  for (uint k = 0u; k < (preview ? 4u : 0u); ++k) {
    uvec2 q = base + uvec2(k & 1u, k >> 1u);
    if (q.x < brdfa_pc.frame.x && q.y < brdfa_pc.frame.y &&
        brdfa_objectId(brdfa_gSurface(brdfa_pixelIndex(q))) == brdfa_pc.target.x)
      blockMask |= 1u << k;
  }
  uint shaded = blockMask != 0u ? uint(findLSB(blockMask)) : 0u;  // the block's pixel to shade
  p = base + uvec2(shaded & 1u, shaded >> 1u);
  surface = brdfa_gSurface(brdfa_pixelIndex(p));
  if (preview) return blockMask != 0u;
  blockMask = 1u;
  return brdfa_objectId(surface) == brdfa_pc.target.x;  // else another object, or background
}

// The shading frame at pixel p, whose G-buffer surface texel is `surface`, in the
// environment's frame (lib/environment.glsl), so samples look the environment up without a
// per-sample rotation; sets the BRDF's texCoord. V is the
// reverse of the view ray through this slice's sub-pixel position, where the raster pass found
// the surface.
void brdfa_surfaceFrame(uvec2 p, uvec2 surface, out vec3 N, out vec3 V, out vec3 X, out vec3 Y) {
#if defined(BRDFA_TANGENT_FRAME) || defined(BRDFA_TEXCOORD)
  uvec4 detail = brdfa_gDetail(brdfa_pixelIndex(p));
  texCoord = uintBitsToFloat(detail.yz);
#else
  texCoord = vec2(0.0);  // never read: the BRDF does not name it (brdf_features.cpp)
#endif
  N = brdfa_toEnvironment(brdfa_octDecode(surface.y));
  V = brdfa_toEnvironment(-brdfa_viewRay(p, brdfa_pc.tone.zw));
  // guard: interpolated normals near a silhouette can face slightly away from the viewer;
  // bend N until V is just above the horizon so every BRDF sees a valid outgoing direction.
  float NdotV = dot(N, V);
  if (NdotV < 1e-3) N = normalize(N + V * (1e-3 - NdotV));
#if defined(BRDFA_TANGENT_FRAME)
  // A missing tangent (detail.w) reads as 0, which brdfa_tangentFrame replaces by a basis from N.
  vec3 tangent = detail.w != 0u ? vec3(0.0) : brdfa_toEnvironment(brdfa_octDecode(detail.x));
  brdfa_tangentFrame(N, tangent, (surface.x & BRDFA_LEFT_HANDED) != 0u ? -1.0 : 1.0, X, Y);
#else
  // The BRDF never reads X or Y (brdf_features.cpp): any orthonormal frame serves the
  // isotropic hemisphere samplers, and this one needs no tangent.
  brdfa_basisFromNormal(N, X, Y);
#endif
}

// Whether sample value c is kept. guard: a NaN or infinite channel makes the channel sum NaN or
// infinite, so one test of the sum drops the sample (a finite sum that overflows float is
// dropped as infinite too).
bool brdfa_sampleKept(vec3 c) {
  float channels = c.x + c.y + c.z;
  return !(isnan(channels) || isinf(channels));
}

// Adds kept sample c of half h to the sums of all kept samples and of half B's, and to their
// counts: no branch or dynamically indexed array per half, which a CPU device turns into
// per-lane memory.
void brdfa_addSample(vec3 c, uint h, inout vec3 sumAll, inout vec3 sumB, inout uint keptAll, inout uint keptB) {
  sumAll += c;
  sumB += c * float(h);
  ++keptAll;
  keptB += h;
}

// The half accumulators' values from the sums of all kept samples and of half B's (half A's is
// the difference) and their counts: rgb the radiance sums at the environment's intensity, a
// the samples kept.
void brdfa_halfValues(vec3 sumAll, vec3 sumB, uint keptAll, uint keptB, out vec4 valueA, out vec4 valueB) {
  float intensity = brdfa_environmentIntensity();
  valueA = vec4((sumAll - sumB) * intensity, float(keptAll - keptB));
  valueB = vec4(sumB * intensity, float(keptB));
}

// For kernels/shade.comp.glsl: writes a pixel's half sums (rgb: radiance sum, a: samples kept)
// to every pixel of blockMask. The first pass after a restart overwrites instead of adding, so
// a change of BRDF or parameters needs no clear of the whole buffer; a preview overwrites too.
void brdfa_writeShaded(uvec2 base, uint blockMask, bool preview, vec4 valueA, vec4 valueB) {
  bool overwrite = brdfa_pc.target.w != 0u;
  for (uint k = 0u; k < (preview ? 4u : 1u); ++k) {
    if ((blockMask & (1u << k)) == 0u) continue;
    uint written = brdfa_pixelIndex(base + uvec2(k & 1u, k >> 1u));
    brdfa_accumulate(0u, written, valueA, overwrite);
    brdfa_accumulate(1u, written, valueB, overwrite);
  }
}
