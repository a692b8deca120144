// GGX (Trowbridge-Reitz) microfacet distribution D(h), normalized: int D (n.h) dw = 1.
// B. Walter, S. Marschner, H. Li, K. Torrance, "Microfacet Models for Refraction through Rough
// Surfaces", EGSR 2007, eq. 33: D = a^2 / (pi ((n.h)^2 (a^2 - 1) + 1)^2), a = alpha_g (not squared).
#include "terms/constants.glsl"

float D_GGX(float NoH, float a)
{
    float a2 = a * a;
    // guard (roughness -> 0): d >= a2 > 0 for a > 0, so no division by zero; a = 0 (a mirror) is
    // not a distribution and gives 0/0, callers keep a > 0.
    float d = NoH * NoH * (a2 - 1.0) + 1.0;
    return a2 / (brdfa_PI * d * d);
}
