// V-cavity (V-groove) masking-shadowing, a function of both directions L and V:
// G = min(1, 2(n.h)(n.v)/(v.h), 2(n.h)(n.l)/(v.h)), symmetric, in [0, 1].
// K. E. Torrance, E. M. Sparrow, JOSA 57(9) 1967 (V-grooves); closed form of J. F. Blinn,
// "Models of Light Reflection for Computer Synthesized Pictures", SIGGRAPH 1977, eq. 3, the
// expression R. L. Cook, K. E. Torrance, ACM TOG 1(1) 1982 use.

float G_VCavity(float NoH, float NoV, float NoL, float VoH)
{
    // guard (grazing angle): v.h -> 0 only when L -> -V (both grazing); cap the ratios there
    float r = 2.0 * NoH / max(VoH, 1e-6);
    return min(1.0, min(r * NoV, r * NoL));
}
