// Smith masking G1 of one direction for GGX; the separable G is G1(n.l) G1(n.v).
// B. Walter et al., EGSR 2007, eq. 34 (in cos form): G1 = 2 (n.x) / ((n.x) + sqrt(a^2 + (1 - a^2)(n.x)^2));
// E. Heitz, JCGT 3(2) 2014, eq. 98 (separable form).

float G1_SmithGGX(float NoX, float a)
{
    float a2 = a * a;
    // guard (roughness -> 0, grazing angle): the denominator is >= n.x + a, > 0 unless both
    // a = 0 and n.x = 0
    return 2.0 * NoX / (NoX + sqrt(a2 + (1.0 - a2) * NoX * NoX));
}
