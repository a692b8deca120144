// Sampling GGX's distribution of visible normals for V, and the density of those draws over
// the sphere: E. Heitz, "Sampling the GGX Distribution of Visible Normals", JCGT 7(4) 2018
// (eqs. 3 and 17), isotropic width a = alpha_g. Frame: T. Duff et al., "Building an
// Orthonormal Basis, Revisited", JCGT 6(1) 2017.
#include "terms/constants.glsl"
#include "terms/d_ggx.glsl"
#include "terms/g_smith_ggx.glsl"

// An orthonormal (T, B, N) for every unit N, +-z included. (A fixed fallback T = +x near +-z
// is not orthogonal to N there: a sample's L is then not unit length and its pdf is wrong.)
void brdfa_frameAround(vec3 N, out vec3 T, out vec3 B)
{
    float sz = N.z >= 0.0 ? 1.0 : -1.0;
    float ca = -1.0 / (sz + N.z);                            // |sz + N.z| >= 1: no division by zero
    float cb = N.x * N.y * ca;
    T = vec3(1.0 + sz * N.x * N.x * ca, sz * cb, -sz * N.x);
    B = vec3(cb, sz + N.y * N.y * ca, -N.y);
}

// V is reflected about a visible normal H = normalize(L + V) drawn with
// D_V(H) = G1(V) (v.h) D(H) / n.v (v.h = (1 + v.l) / |L + V| >= 0 always), and the
// reflection's Jacobian 1/(4 v.h) gives pdf(L) = G1(V) D(H) / (4 n.v). Directions reflected
// below the horizon count as drawn.
float pdfGGXVNDF(vec3 L, vec3 V, vec3 N, float a)
{
    float NoV = dot(N, V);
    if (NoV <= 0.0) return 0.0;                 // viewer below the horizon: nothing is drawn
    vec3 h = L + V;
    if (dot(h, h) <= 0.0) return 0.0;           // guard: L = -V has no half vector (measure zero)
    float NoH = dot(N, normalize(h));
    if (NoH <= 0.0) return 0.0;                 // visible normals lie above the horizon
    return G1_SmithGGX(NoV, a) * D_GGX(NoH, a) / (4.0 * NoV);   // NoV > 0 here
}

// L drawn with density pdfGGXVNDF; vec3(0) when V is below the horizon or L is reflected below
// it (the draw is lost, and counted in the density).
vec3 sampleGGXVNDF(vec2 u, vec3 V, vec3 N, float a)
{
    vec3 T, B;
    brdfa_frameAround(N, T, B);
    vec3 v = vec3(dot(V, T), dot(V, B), dot(V, N));
    if (v.z <= 0.0) return vec3(0.0);                      // viewer below the horizon
    vec3 vh = normalize(vec3(a * v.x, a * v.y, v.z));       // stretch to the hemisphere configuration
    float lensq = vh.x * vh.x + vh.y * vh.y;
    vec3 t1 = lensq > 0.0 ? vec3(-vh.y, vh.x, 0.0) * inversesqrt(lensq) : vec3(1.0, 0.0, 0.0);  // guard: v = n
    vec3 t2 = cross(vh, t1);
    float r = sqrt(u.x);
    float phi = 2.0 * brdfa_PI * u.y;
    float p1 = r * cos(phi);
    float p2 = r * sin(phi);
    float s = 0.5 * (1.0 + vh.z);
    p2 = (1.0 - s) * sqrt(max(0.0, 1.0 - p1 * p1)) + s * p2;   // guard: rounding below 0
    vec3 nh = p1 * t1 + p2 * t2 + sqrt(max(0.0, 1.0 - p1 * p1 - p2 * p2)) * vh;
    vec3 h = normalize(vec3(a * nh.x, a * nh.y, max(0.0, nh.z)));   // unstretch
    vec3 l = reflect(-v, h);
    if (l.z <= 0.0) return vec3(0.0);                       // reflected below the horizon
    vec3 L = T * l.x + B * l.y + N * l.z;
    // guard: rounding of the frame change can put an L with l.z ~ 1e-8 on the horizon
    return dot(N, L) > 0.0 ? L : vec3(0.0);
}
