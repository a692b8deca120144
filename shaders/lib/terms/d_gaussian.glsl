// Gaussian distribution of facet angles D(h) ~ exp(-(alpha/sigma)^2), alpha = angle(n, h),
// normalized so that int D (n.h) dw = 1 over all alpha:
// 2 pi int_0^inf exp(-a^2/s^2) sin(a) cos(a) da = pi s Dawson(s). (The tail beyond pi/2,
// dropped by the integral over the hemisphere, is < 1e-3 for s <= 0.6.)
// K. E. Torrance, E. M. Sparrow, "Theory for Off-Specular Reflection From Roughened Surfaces",
// JOSA 57(9) 1967, eq. 8.
#include "terms/constants.glsl"

// Dawson's integral F(x) = exp(-x^2) int_0^x exp(t^2) dt by its Maclaurin series
// sum (-1)^k 2^k x^(2k+1) / (2k+1)!!; 10 terms are exact to float precision for x <= 0.6.
float Dawson(float x)
{
    float x2 = x * x;
    float term = x;
    float sum = x;
    for (int k = 1; k < 10; ++k) {
        term *= -2.0 * x2 / float(2 * k + 1);
        sum += term;
    }
    return sum;
}

float D_Gaussian(float NoH, float s)
{
    float a = acos(min(NoH, 1.0));   // guard: rounding can make n.h slightly > 1 (acos undefined)
    float t = a / s;
    // exponent overflow: the exponent is <= 0, so exp never overflows
    return exp(-t * t) / (brdfa_PI * s * Dawson(s));
}
