// Display encoding: exposure, clamp, then the sRGB transfer function (IEC 61966-2-1).
float brdfa_srgbEncode(float c) {
  return c <= 0.0031308 ? 12.92 * c : 1.055 * pow(c, 1.0 / 2.4) - 0.055;
}

uint brdfa_packSrgb8(vec3 linear, float exposureScale) {
  // guard: NaN never reaches here (the integrator drops it), but clamp handles +Inf and
  // negative radiance from a BRDF that returns negative values.
  vec3 c = clamp(linear * exposureScale, 0.0, 1.0);
  uvec3 b = uvec3(vec3(brdfa_srgbEncode(c.r), brdfa_srgbEncode(c.g), brdfa_srgbEncode(c.b)) * 255.0 + 0.5);
  return b.r | (b.g << 8) | (b.b << 16) | (255u << 24);
}

float brdfa_luminance(vec3 c) { return dot(c, vec3(0.2126, 0.7152, 0.0722)); }  // Rec. 709
