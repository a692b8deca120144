// Schlick's approximation of Smith GGX masking G1 of one direction, k = alpha/2:
// G1 = (n.x) / ((n.x)(1 - k) + k). C. Schlick, CGF 13(3) 1994; k = alpha/2 for GGX,
// B. Karis, "Real Shading in Unreal Engine 4", SIGGRAPH 2013 course.
// The separable G is G1(n.l) G1(n.v).

float G1_SchlickGGX(float NoX, float a)
{
    float k = 0.5 * a;
    // guard (roughness -> 0, grazing angle): the denominator is >= min(n.x, k), > 0 unless both
    // a = 0 and n.x = 0
    return NoX / (NoX * (1.0 - k) + k);
}
