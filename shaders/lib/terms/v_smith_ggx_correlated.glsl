// Height-correlated Smith masking-shadowing for GGX divided by 4 (n.l)(n.v), the visibility
// term V = G2 / (4 (n.l)(n.v)). E. Heitz, "Understanding the Masking-Shadowing Function in
// Microfacet-Based BRDFs", JCGT 3(2) 2014, eq. 99; written as Filament's V_SmithGGXCorrelated.
// Exact, and finite as either cosine -> 0.

float V_SmithGGXCorrelated(float NoV, float NoL, float a)
{
    float a2 = a * a;
    float lambdaV = NoL * sqrt(NoV * NoV * (1.0 - a2) + a2);
    float lambdaL = NoV * sqrt(NoL * NoL * (1.0 - a2) + a2);
    // guard (grazing angle): both cosines at the horizon at once (0/0); the true limit is
    // irrelevant there because the integrand is multiplied by n.l = 0.
    return 0.5 / max(lambdaV + lambdaL, 1e-20);
}
