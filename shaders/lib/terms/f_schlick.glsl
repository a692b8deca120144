// Schlick's Fresnel approximation F = F0 + (1 - F0)(1 - c)^5, c = v.h (= l.h), on the half
// vector (not n.v). C. Schlick, "An Inexpensive BRDF Model for Physically-based Rendering",
// CGF 13(3) 1994, eq. 24.

vec3 F_Schlick(float VoH, vec3 f0)
{
    float m = clamp(1.0 - VoH, 0.0, 1.0);   // guard: rounding can make v.h slightly > 1 (or < 0)
    float m2 = m * m;
    return f0 + (1.0 - f0) * (m2 * m2 * m);
}
