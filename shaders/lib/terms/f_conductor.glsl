// Exact unpolarized Fresnel reflectance of a conductor with complex IOR eta + i k per channel,
// on c = v.h. M. Born, E. Wolf, Principles of Optics, sec. 14.2; the real-arithmetic form of
// M. Pharr, W. Jakob, G. Humphreys, pbrt-v3, sec. 8.2.1 (FrConductor): with
// a^2 + b^2 = sqrt((eta^2 - k^2 - sin^2)^2 + 4 eta^2 k^2),
// Rs = (a^2+b^2 + cos^2 - 2a cos)/(a^2+b^2 + cos^2 + 2a cos),
// Rp = Rs (cos^2 (a^2+b^2) + sin^4 - 2a cos sin^2)/(cos^2 (a^2+b^2) + sin^4 + 2a cos sin^2).

vec3 F_Conductor(float c, vec3 eta, vec3 k)
{
    float cos2 = c * c;
    float sin2 = 1.0 - cos2;
    vec3 eta2 = eta * eta;
    vec3 k2 = k * k;
    vec3 t0 = eta2 - k2 - sin2;
    vec3 a2plusb2 = sqrt(t0 * t0 + 4.0 * eta2 * k2);
    vec3 t1 = a2plusb2 + cos2;
    vec3 a = sqrt(max(0.5 * (a2plusb2 + t0), 0.0));   // guard: rounding makes the root argument < 0
    vec3 t2 = 2.0 * c * a;
    vec3 Rs = (t1 - t2) / max(t1 + t2, vec3(1e-12));   // guard (grazing angle): c = 0 with eta = k = 0 (0/0)
    vec3 t3 = cos2 * a2plusb2 + sin2 * sin2;
    vec3 t4 = t2 * sin2;
    vec3 Rp = Rs * (t3 - t4) / max(t3 + t4, vec3(1e-12));   // guard: c = 1 with a2plusb2 = 0 (0/0)
    return 0.5 * (Rp + Rs);
}
