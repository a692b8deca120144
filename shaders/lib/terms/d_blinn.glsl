// Normalized Blinn-Phong microfacet distribution D(h) = (n+2)/(2 pi) (n.h)^n,
// int D (n.h) dw = 1. J. F. Blinn, "Models of Light Reflection for Computer Synthesized
// Pictures", SIGGRAPH 1977; normalization as in B. Walter et al., EGSR 2007, eq. 30.
#include "terms/constants.glsl"

float D_Blinn(float NoH, float e)
{
    // guard: none needed for n.h >= 0 and e >= 1 (pow of a negative base is undefined; callers
    // clamp n.h to [0, 1])
    return (e + 2.0) / (2.0 * brdfa_PI) * pow(NoH, e);
}
