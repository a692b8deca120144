// Exact unpolarized Fresnel reflectance of a dielectric with relative index eta, on c = v.h.
// R. L. Cook, K. E. Torrance, "A Reflectance Model for Computer Graphics", ACM TOG 1(1) 1982,
// Appendix (from Sparrow & Cess 1978): g^2 = eta^2 + c^2 - 1,
// F = 1/2 (g-c)^2/(g+c)^2 (1 + ((c(g+c) - 1)/(c(g-c) + 1))^2); total internal reflection gives 1.

float F_Dielectric(float c, float eta)
{
    float g2 = eta * eta + c * c - 1.0;
    if (g2 < 0.0) return 1.0;                          // total internal reflection (eta < 1)
    float g = sqrt(g2);
    float gpc = max(g + c, 1e-12);                     // guard (grazing angle): eta = 1, c = 0 is 0/0
    float a = (g - c) / gpc;
    float b = (c * gpc - 1.0) / (c * (g - c) + 1.0);   // denominator >= 1 since g >= c
    return 0.5 * a * a * (1.0 + b * b);
}
