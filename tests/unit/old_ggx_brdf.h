// The GGX file as it was before its sampler's frame was fixed (git show 3f87277:shaders/brdfs/ggx.brdf), kept verbatim
// for the tests: its sampler builds the frame around N with the fallback tangent T = +x when
// |N.z| >= 0.999, which is not orthogonal to N there (L is then not unit length and the pdf does
// not describe the draws). The check at N = +z alone could not see it.
#pragma once

namespace brdfa::testdata {

inline constexpr const char* kOldGgxBrdf = R"BRDF(analytic
# ggx: microfacet specular reflection with the GGX (Trowbridge-Reitz) distribution.
# Citation: B. Walter, S. Marschner, H. Li, K. Torrance, "Microfacet Models for Refraction
#   through Rough Surfaces", EGSR 2007 (D); E. Heitz, "Understanding the Masking-Shadowing
#   Function in Microfacet-Based BRDFs", JCGT 3(2) 2014 (height-correlated Smith G2);
#   C. Schlick, "An Inexpensive BRDF Model for Physically-based Rendering", CGF 1994 (F).
# Reciprocal; energy <= 1 (single scattering loses energy at high roughness).
# Sampling: visible normals, E. Heitz, "Sampling the GGX Distribution of Visible Normals",
#   JCGT 7(4) 2018.

::begin parameters
float roughness 0.001 1 0.3    # GGX width alpha_g (Walter 2007), not squared
color F0 0.95 0.64 0.54        # Fresnel reflectance at normal incidence
::end parameters

::begin shader
const float PI = 3.14159265358979323846;

// Walter 2007, eq. 33: D(m) = a^2 / (pi cos^4(t) (a^2 + tan^2(t))^2), rewritten in cos(t).
float D_GGX(float NoH, float a)
{
    float a2 = a * a;
    float d = NoH * NoH * (a2 - 1.0) + 1.0;   // >= a2 > 0 for a > 0: no division by zero
    return a2 / (PI * d * d);
}

// Height-correlated Smith masking-shadowing divided by 4 (n.l)(n.v) (Heitz 2014 eq. 99;
// written as in Filament's V_SmithGGXCorrelated). Exact, and finite as either cosine -> 0.
float V_SmithGGXCorrelated(float NoV, float NoL, float a)
{
    float a2 = a * a;
    float lambdaV = NoL * sqrt(NoV * NoV * (1.0 - a2) + a2);
    float lambdaL = NoV * sqrt(NoL * NoL * (1.0 - a2) + a2);
    // guard: both cosines at the horizon at once (0/0); the true limit is irrelevant there
    // because the integrand is multiplied by n.l = 0.
    return 0.5 / max(lambdaV + lambdaL, 1e-20);
}

// Schlick 1994: F = F0 + (1 - F0) (1 - v.h)^5, on the half vector (not n.v).
vec3 F_Schlick(float VoH, vec3 f0)
{
    float m = clamp(1.0 - VoH, 0.0, 1.0);   // guard: rounding can make v.h slightly > 1
    float m2 = m * m;
    return f0 + (1.0 - f0) * (m2 * m2 * m);
}

vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y)
{
    float NoL = dot(N, L);
    float NoV = dot(N, V);
    if (NoL <= 0.0 || NoV <= 0.0) return vec3(0.0);   // below the horizon: no reflection
    vec3 H = normalize(L + V);                          // L + V != 0 when both are above N
    float NoH = clamp(dot(N, H), 0.0, 1.0);
    // v.h = l.h = cos of half the angle between L and V. This symmetric form keeps
    // f(L,V) == f(V,L) in float too (dot(V,H) and dot(L,H) round differently).
    float VoH = clamp(sqrt(max(0.5 + 0.5 * dot(L, V), 0.0)), 0.0, 1.0);   // guard: rounding below 0
    return D_GGX(NoH, roughness) * V_SmithGGXCorrelated(NoV, NoL, roughness) * F_Schlick(VoH, F0);
}
::end shader

::begin sample
// Smith G1 for GGX (Walter 2007 eq. 34, in cos form): the masking of one direction.
float G1_SmithGGX(float NoV, float a)
{
    float a2 = a * a;
    return 2.0 * NoV / (NoV + sqrt(a2 + (1.0 - a2) * NoV * NoV));
}

// The density of sampleBRDF's draws over the whole sphere (Heitz 2018 eqs. 3 and 17): V is
// reflected about a visible normal H = normalize(L + V) drawn with D_V(H) = G1(V) (v.h) D(H) / n.v
// (v.h = (1 + v.l) / |L + V| >= 0 always), and the reflection's Jacobian 1/(4 v.h) gives
// pdf(L) = G1(V) D(H) / (4 n.v). Directions reflected below the horizon count as drawn.
float pdfBRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y)
{
    float NoV = dot(N, V);
    if (NoV <= 0.0) return 0.0;                 // viewer below the horizon: nothing is drawn
    vec3 h = L + V;
    if (dot(h, h) <= 0.0) return 0.0;           // guard: L = -V has no half vector (measure zero)
    float NoH = dot(N, normalize(h));
    if (NoH <= 0.0) return 0.0;                 // visible normals lie above the horizon
    return G1_SmithGGX(NoV, roughness) * D_GGX(NoH, roughness) / (4.0 * NoV);   // NoV > 0 here
}

// Heitz 2018: draw a visible microfacet normal for V, reflect V about it; its pdf is pdfBRDF.
vec3 sampleBRDF(vec2 u, vec3 V, vec3 N, vec3 X, vec3 Y, out vec3 L, out float pdf)
{
    // The lobe is isotropic: any frame around N serves.
    vec3 T = abs(N.z) < 0.999 ? normalize(cross(vec3(0.0, 0.0, 1.0), N)) : vec3(1.0, 0.0, 0.0);  // guard: N ~ z
    vec3 B = cross(N, T);
    vec3 v = vec3(dot(V, T), dot(V, B), dot(V, N));
    L = vec3(0.0);
    pdf = 0.0;
    if (v.z <= 0.0) return vec3(0.0);                      // viewer below the horizon
    float a = roughness;
    vec3 vh = normalize(vec3(a * v.x, a * v.y, v.z));       // stretch to the hemisphere configuration
    float lensq = vh.x * vh.x + vh.y * vh.y;
    vec3 t1 = lensq > 0.0 ? vec3(-vh.y, vh.x, 0.0) * inversesqrt(lensq) : vec3(1.0, 0.0, 0.0);  // guard: v = n
    vec3 t2 = cross(vh, t1);
    float r = sqrt(u.x);
    float phi = 2.0 * PI * u.y;
    float p1 = r * cos(phi);
    float p2 = r * sin(phi);
    float s = 0.5 * (1.0 + vh.z);
    p2 = (1.0 - s) * sqrt(max(0.0, 1.0 - p1 * p1)) + s * p2;   // guard: rounding below 0
    vec3 nh = p1 * t1 + p2 * t2 + sqrt(max(0.0, 1.0 - p1 * p1 - p2 * p2)) * vh;
    vec3 h = normalize(vec3(a * nh.x, a * nh.y, max(0.0, nh.z)));   // unstretch
    vec3 l = reflect(-v, h);
    if (l.z <= 0.0) return vec3(0.0);                       // reflected below the horizon
    L = T * l.x + B * l.y + N * l.z;
    pdf = pdfBRDF(L, V, N, X, Y);
    return BRDF(L, V, N, X, Y);
}
::end sample
)BRDF";

}  // namespace brdfa::testdata
