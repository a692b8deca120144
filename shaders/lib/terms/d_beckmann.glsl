// Beckmann microfacet distribution D(h), normalized: int D (n.h) dw = 1.
// P. Beckmann, A. Spizzichino, The Scattering of Electromagnetic Waves from Rough Surfaces, 1963;
// as in R. L. Cook, K. E. Torrance, ACM TOG 1(1) 1982 and B. Walter et al., EGSR 2007, eq. 25:
// D = exp(-tan^2(t)/m^2) / (pi m^2 cos^4(t)), t = angle(n, h), m the RMS slope.
#include "terms/constants.glsl"

float D_Beckmann(float NoH, float mm)
{
    // guard (grazing angle): h on the horizon (grazing L and V) makes tan^2 and 1/cos^4 0/0
    float c2 = max(NoH * NoH, 1e-12);
    float tan2 = (1.0 - c2) / c2;
    float m2 = mm * mm;
    // exponent overflow: the exponent is <= 0, so exp never overflows
    return exp(-tan2 / m2) / (brdfa_PI * m2 * c2 * c2);
}
