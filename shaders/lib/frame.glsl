// Local shading frames.

// Orthonormal basis from a unit normal, without a branch-free singularity: Duff et al. 2017,
// "Building an Orthonormal Basis, Revisited" (JCGT 6(1)).
void brdfa_basisFromNormal(vec3 n, out vec3 x, out vec3 y) {
  float s = n.z >= 0.0 ? 1.0 : -1.0;
  float a = -1.0 / (s + n.z);
  float b = n.x * n.y * a;
  x = vec3(1.0 + s * n.x * n.x * a, s * b, -s * n.x);
  y = vec3(b, s + n.y * n.y * a, -n.y);
}

// Tangent frame from an interpolated normal and tangent. Gram-Schmidt re-orthogonalizes the
// tangent (interpolation breaks orthogonality); a tangent nearly parallel to N (degenerate UVs)
// falls back to a basis built from N alone so X, Y are always unit and orthogonal.
void brdfa_tangentFrame(vec3 n, vec3 t, float handedness, out vec3 x, out vec3 y) {
  vec3 tt = t - n * dot(n, t);
  float len2 = dot(tt, tt);
  if (len2 < 1e-8) {  // guard: degenerate or missing tangent
    brdfa_basisFromNormal(n, x, y);
    return;
  }
  x = tt * inversesqrt(len2);
  y = cross(n, x) * handedness;
}
