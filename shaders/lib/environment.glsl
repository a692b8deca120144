// Incident radiance from the environment, in world space (+Y up).
//
// The environment's rotation and intensity are applied per pixel, not per sample: the shade
// kernel turns its whole frame (N, V, X, Y) into the environment's frame once, which leaves
// every BRDF value unchanged (a BRDF depends only on the angles between its arguments), and
// scales the pixel's sum by the intensity.

// World direction -> environment map direction: a turn by -rotation about +Y, which turns the
// environment by +rotation.
vec3 brdfa_toEnvironment(vec3 dir) {
  float c = brdfa_pc.env.y, s = brdfa_pc.env.z;
  return vec3(c * dir.x - s * dir.z, dir.y, s * dir.x + c * dir.z);
}

// Radiance arriving from `envDir` (already in the environment's frame) at intensity 1.
// A constant environment (the furnace) compiles to a constant: no texture lookup at all.
vec3 brdfa_environmentUnit(vec3 envDir) {
#if defined(BRDFA_ENV_CONSTANT)
  return vec3(1.0);
#else
  return textureLod(brdfa_envMap, envDir, 0.0).rgb;
#endif
}

float brdfa_environmentIntensity() { return brdfa_pc.env.x; }
