// Smith masking G1 of one direction for Beckmann, by the rational fit of B. Walter et al.,
// EGSR 2007, eq. 27 (B. Smith, IEEE TAP 15(5) 1967): c = (n.x) / (m sqrt(1 - (n.x)^2)),
// G1 = (3.535 c + 2.181 c^2) / (1 + 2.276 c + 2.577 c^2) for c < 1.6, else 1.
// The separable G is G1(n.l) G1(n.v).

float G1_SmithBeckmann(float NoX, float mm)
{
    float s = sqrt(max(0.0, 1.0 - NoX * NoX));   // guard: rounding makes 1 - cos^2 < 0
    // c >= 1.6; also guards normal incidence (s = 0, c = inf) and roughness -> 0
    if (s * 1.6 * mm <= NoX) return 1.0;
    float c = NoX / (mm * s);                    // s > 0 and mm > 0 here: no division by zero
    return (3.535 * c + 2.181 * c * c) / (1.0 + 2.276 * c + 2.577 * c * c);
}
