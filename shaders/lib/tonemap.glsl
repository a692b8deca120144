// Display encoding of PNG frames: exposure, tone map, then the sRGB transfer function
// (IEC 61966-2-1). Float outputs (PFM, EXR) never pass through here. renderer/src/render/host_resolve.cpp
// computes exactly the same on the host (tests compare the two paths).
float brdfa_srgbEncode(float c) {
  return c <= 0.0031308 ? 12.92 * c : 1.055 * pow(c, 1.0 / 2.4) - 0.055;
}

// Tone maps of the exposed radiance e = L * 2^exposure, per channel, into [0, 1].
// Guards: negative radiance (a BRDF returning negative values) maps to 0, and the curves are
// evaluated on values bounded far above where they reach 1, so +Inf maps to 1, never to
// Inf / Inf = NaN.
const float BRDFA_TONE_MAX = 1.0e6;

// Clamp: min(e, 1).
vec3 brdfa_toneClamp(vec3 e) { return min(e, vec3(1.0)); }

// Reinhard, Stark, Shirley, Ferwerda 2002, "Photographic Tone Reproduction for Digital Images",
// eq. 3: e / (1 + e), applied per channel.
vec3 brdfa_toneReinhard(vec3 e) { return e / (1.0 + e); }

// Narkowicz 2015, "ACES Filmic Tone Mapping Curve": a rational fit of the ACES RRT + ODT,
// (e (a e + b)) / (e (c e + d) + f) with a = 2.51, b = 0.03, c = 2.43, d = 0.59, f = 0.14,
// clamped to [0, 1]. Applied as published, without his optional 0.6 pre-scale.
vec3 brdfa_toneAces(vec3 e) {
  const float a = 2.51, b = 0.03, c = 2.43, d = 0.59, f = 0.14;
  return clamp((e * (a * e + b)) / (e * (c * e + d) + f), 0.0, 1.0);
}

// mode: 0 clamp, 1 reinhard, 2 aces (brdfa::ToneMap; brdfa_pc.tone.y).
vec3 brdfa_toneMap(vec3 e, float mode) {
  e = clamp(e, 0.0, BRDFA_TONE_MAX);
  if (mode > 1.5) return brdfa_toneAces(e);
  if (mode > 0.5) return brdfa_toneReinhard(e);
  return brdfa_toneClamp(e);
}

uint brdfa_packSrgb8(vec3 linear, float exposureScale, float toneMode) {
  // guard: NaN never reaches here (the integrator drops it); clamp to [0, 1] after the tone
  // map keeps rounding from carrying a code past 255.
  vec3 c = clamp(brdfa_toneMap(linear * exposureScale, toneMode), 0.0, 1.0);
  uvec3 b = uvec3(vec3(brdfa_srgbEncode(c.r), brdfa_srgbEncode(c.g), brdfa_srgbEncode(c.b)) * 255.0 + 0.5);
  return b.r | (b.g << 8) | (b.b << 16) | (255u << 24);
}

float brdfa_luminance(vec3 c) { return dot(c, vec3(0.2126, 0.7152, 0.0722)); }  // Rec. 709
