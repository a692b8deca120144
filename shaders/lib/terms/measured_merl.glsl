// A measured isotropic BRDF in MERL's layout: W. Matusik, H. Pfister, M. Brand, L. McMillan,
// "A Data-Driven Reflectance Model", SIGGRAPH 2003; angles after S. Rusinkiewicz, "A New Change
// of Variables for Efficient BRDF Representation", EGWR 1998. The table is the object's
// measured asset (set 1, binding 6): f_r in 1/sr, 3 floats per bin at bin
// phi_d + 180 theta_d + 16200 theta_h, all three negative where the bin has no data.
// The lookup is brdfa/measured.h's lookupMerlInterpolated: trilinear between bin centres in
// (sqrt-scaled theta_h, theta_d, phi_d), clamped in theta, periodic in phi_d, bins without data
// left out and the other weights renormalised. After the table, two floats: the sampling
// proposal brdfa/measured.h's fitMerlLobe chose for it (a GGX lobe's width, and the
// probability of drawing from it instead of the cosine).
#include "terms/constants.glsl"
#include "terms/sample_ggx_vndf.glsl"

layout(std430, set = 1, binding = 6) readonly buffer BrdfaMeasured { float brdfa_measuredTable[]; };

const int brdfa_kMerlBins = 1458000;

// Bin (h, d, p)'s value and 1, or 0 where it has no data.
vec4 brdfa_merlBin(int h, int d, int p)
{
    int i = 3 * (p + 180 * d + 16200 * h);
    vec3 v = vec3(brdfa_measuredTable[i], brdfa_measuredTable[i + 1], brdfa_measuredTable[i + 2]);
    return v.x < 0.0 ? vec4(0.0) : vec4(v, 1.0);
}

vec3 measuredMERL(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y)
{
    // guard (no table bound: an object whose BRDF is not measured binds a short stand-in).
    if (brdfa_measuredTable.length() < 3 * brdfa_kMerlBins + 2) return vec3(0.0);
    // Measured above the horizon only.
    if (dot(N, L) <= 0.0 || dot(N, V) <= 0.0) return vec3(0.0);
    vec3 H = normalize(L + V);   // L + V != 0 when both are above N
    float cosH = clamp(dot(N, H), -1.0, 1.0);
    float thetaH = acos(cosH);
    float thetaD = acos(clamp(dot(L, H), -1.0, 1.0));
    // The difference frame about H: x away from N's projection (MERL rotates N to
    // (-sin theta_h, 0, cos theta_h)), y = H x x.
    vec3 t = N - cosH * H;
    // guard (theta_h -> 0): H = N leaves x undefined; any tangent serves an isotropic table.
    vec3 ex = dot(t, t) > 1e-12 ? -normalize(t) : normalize(X - dot(X, H) * H);
    vec3 ey = cross(H, ex);
    float phiD = atan(dot(L, ey), dot(L, ex));
    if (phiD < 0.0) phiD += brdfa_PI;   // phi_d and phi_d + pi share a bin (reciprocity)

    // Continuous bin coordinates, bin i's centre at i.
    float xh = clamp(90.0 * sqrt(thetaH / (0.5 * brdfa_PI)) - 0.5, 0.0, 89.0);
    float xd = clamp(thetaD / (0.5 * brdfa_PI) * 90.0 - 0.5, 0.0, 89.0);
    float xp = phiD / brdfa_PI * 180.0 - 0.5;
    int h0 = min(int(xh), 89), d0 = min(int(xd), 89);
    int h1 = min(h0 + 1, 89), d1 = min(d0 + 1, 89);
    float fh = xh - float(h0), fd = xd - float(d0);
    float pf = floor(xp);
    int p0 = (int(pf) + 180) % 180, p1 = (p0 + 1) % 180;
    float fp = xp - pf;

    vec4 sum = (1.0 - fh) * (1.0 - fd) * ((1.0 - fp) * brdfa_merlBin(h0, d0, p0) + fp * brdfa_merlBin(h0, d0, p1))
             + (1.0 - fh) * fd * ((1.0 - fp) * brdfa_merlBin(h0, d1, p0) + fp * brdfa_merlBin(h0, d1, p1))
             + fh * (1.0 - fd) * ((1.0 - fp) * brdfa_merlBin(h1, d0, p0) + fp * brdfa_merlBin(h1, d0, p1))
             + fh * fd * ((1.0 - fp) * brdfa_merlBin(h1, d1, p0) + fp * brdfa_merlBin(h1, d1, p1));
    // guard (every neighbour without data): nothing measured here.
    return sum.w > 0.0 ? sum.xyz / sum.w : vec3(0.0);
}

// The proposal: (GGX width, probability of the lobe), kept inside the range the host clamps
// them to, so that a damaged tail can never divide by zero below.
vec2 brdfa_merlLobe()
{
    int i = 3 * brdfa_kMerlBins;
    return vec2(clamp(brdfa_measuredTable[i], 0.005, 1.0), clamp(brdfa_measuredTable[i + 1], 0.05, 0.95));
}

// The density of sampleMeasuredMERL's draws over the sphere: the mixture of the lobe's visible
// normals and the cosine. Any proposal is unbiased; a good one only lowers the variance.
float pdfMeasuredMERL(vec3 L, vec3 V, vec3 N)
{
    // guard (no table bound): nothing is drawn.
    if (brdfa_measuredTable.length() < 3 * brdfa_kMerlBins + 2) return 0.0;
    vec2 lobe = brdfa_merlLobe();
    return lobe.y * pdfGGXVNDF(L, V, N, lobe.x) + (1.0 - lobe.y) * max(dot(N, L), 0.0) / brdfa_PI;
}

// Draws L from the lobe with probability lobe.y, else from the cosine (Malley); returns f and
// sets pdf to pdfMeasuredMERL. L = 0 and pdf = 0 when nothing is drawn (viewer below the
// horizon, a lobe draw reflected below it).
vec3 sampleMeasuredMERL(vec2 u, vec3 V, vec3 N, vec3 X, vec3 Y, out vec3 L, out float pdf)
{
    L = vec3(0.0);
    pdf = 0.0;
    if (brdfa_measuredTable.length() < 3 * brdfa_kMerlBins + 2 || dot(N, V) <= 0.0) return vec3(0.0);
    vec2 lobe = brdfa_merlLobe();
    if (u.x < lobe.y) {
        L = sampleGGXVNDF(vec2(u.x / lobe.y, u.y), V, N, lobe.x);
    } else {
        float r = sqrt((u.x - lobe.y) / (1.0 - lobe.y));
        float phi = 2.0 * brdfa_PI * u.y;
        vec3 T, B;
        brdfa_frameAround(N, T, B);
        L = T * (r * cos(phi)) + B * (r * sin(phi)) + N * sqrt(max(0.0, 1.0 - r * r));
    }
    // guard: grazing draws can round onto or below the horizon
    if (dot(N, L) <= 0.0) { L = vec3(0.0); return vec3(0.0); }
    pdf = pdfMeasuredMERL(L, V, N);
    return measuredMERL(L, V, N, X, Y);
}
