// Measured isotropic BRDFs in MERL's `.binary` layout (Matusik, Pfister, Brand and McMillan,
// "A Data-Driven Reflectance Model", SIGGRAPH 2003): reading and validating a file, MERL's own
// bin lookup, an interpolated lookup, and writing a table in that layout. No Vulkan and no HTTP.
//
// The layout: three int32 (90, 90, 180: theta_h, theta_d and phi_d bins), then 3 x 1,458,000
// float64, planar R then G then B, bin (theta_h, theta_d, phi_d) at phi_d + 180 theta_d +
// 16200 theta_h, each channel scaled by 1/1500, 1.15/1500 and 1.66/1500 to give 1/sr.
// theta_h is binned by the square-root mapping (bin i holds theta_h in
// [(i/90)^2, ((i+1)/90)^2) x pi/2), theta_d and phi_d linearly over [0, pi/2) and [0, pi);
// phi_d and phi_d + pi share a bin (reciprocity). A negative value marks a bin without data.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "brdfa/brdf.h"
#include "brdfa/result.h"

namespace brdfa {

constexpr int kMerlThetaHBins = 90;
constexpr int kMerlThetaDBins = 90;
constexpr int kMerlPhiDBins = 180;
constexpr size_t kMerlBins = size_t(kMerlThetaHBins) * kMerlThetaDBins * kMerlPhiDBins;  // 1,458,000
constexpr size_t kMerlFileBytes = 3 * sizeof(int32_t) + 3 * kMerlBins * sizeof(double);
// Per channel: a stored value times this is f_r in 1/sr.
constexpr double kMerlScale[3] = {1.0 / 1500.0, 1.15 / 1500.0, 1.66 / 1500.0};

// A bin of the table: theta_h, theta_d, phi_d indices.
struct MerlBin {
  int thetaH = 0, thetaD = 0, phiD = 0;
};
size_t merlIndex(const MerlBin& bin);  // phi_d + 180 theta_d + 16200 theta_h

// A measured table as the renderer holds it: f_r in 1/sr, RGB interleaved per bin (MERL's
// scale applied, float32). A bin without data has all three channels at -1.
struct MeasuredTable {
  std::vector<float> rgb;  // 3 * kMerlBins
  size_t validBins = 0;
  // The sampling proposal fitMerlLobe chose: a GGX lobe of width lobeAlpha, drawn with
  // probability lobeWeight, else the cosine.
  float lobeAlpha = 0.3f, lobeWeight = 0.5f;
  bool valid(size_t bin) const { return rgb[3 * bin] >= 0.0f; }
  uint64_t bytes() const { return rgb.size() * sizeof(float); }
};

// True when `bytes` start with MERL's header (90, 90, 180), whatever their length.
bool hasMerlHeader(std::string_view bytes);

// Reads a whole MERL file. A bin with a negative value in any channel has no data. InvalidArgument,
// with a message a user can act on, for a wrong size (truncated or trailing bytes), a wrong
// header, a NaN or infinite value (naming its bin and channel), or no bin with data at all.
// Thread-safe; a 35 MB file takes a few tens of milliseconds.
Result<MeasuredTable> readMerl(std::string_view bytes);

// A proposal to importance-sample the table with: a GGX lobe of width alpha in [0.005, 1],
// drawn with probability weight in [0.1, 0.9], else the cosine. From the green channel's profile
// over theta_h at the smallest theta_d (phi_d averaged), read as a GGX D above a diffuse floor:
// alpha from the profile's half-width above the floor (exact for a pure GGX D), the weight
// from the two parts' energies (a narrow GGX lobe of peak f reflects about 4 pi alpha^2 f, the
// floor pi f). Any proposal leaves the estimate unbiased: the mixture's pdf is exact.
struct MerlLobe {
  float alpha = 0.3f, weight = 0.5f;
};
MerlLobe fitMerlLobe(const MeasuredTable& table);

// Writes `planar` (3 x kMerlBins stored values, R then G then B, MERL's scale not applied) as a
// MERL file. For tests and examples: any values are written as given.
std::string writeMerl(const std::vector<double>& planar);

// Rusinkiewicz's half/difference angles ("A New Change of Variables for Efficient BRDF
// Representation", 1998) of unit directions L and V in the local frame (normal +z, tangent +x).
// phiD is folded into [0, pi) as MERL stores it, so that swapping L and V gives the same angles.
struct HalfDiff {
  double thetaH = 0, thetaD = 0, phiD = 0;
};
HalfDiff halfDiffFromDirections(const Vec3& L, const Vec3& V);
HalfDiff halfDiffFromDirections(const std::array<double, 3>& L, const std::array<double, 3>& V);
// The inverse, with phi_h = 0: the unit directions whose half/difference angles are `hd`.
void directionsFromHalfDiff(const HalfDiff& hd, std::array<double, 3>& L, std::array<double, 3>& V);

// The bin MERL's reference reader (BRDFRead.cpp) looks up for these angles.
MerlBin merlBinOf(const HalfDiff& hd);
// The angles at a bin's centre: its theta_h at (i + 1/2)^2 on the square-root scale.
HalfDiff merlBinCentre(const MerlBin& bin);

// f_r(L, V) from the table, L and V unit vectors in the local frame (normal +z), per channel:
//  - nearest: the value of merlBinOf's bin (0 where it has no data);
//  - interpolated: trilinear in (sqrt-scaled theta_h, theta_d, phi_d) between bin centres,
//    clamped at the theta edges and periodic in phi_d; bins without data are left out and the
//    others' weights renormalised (0 where none of the 8 has data). Exact at bin centres and
//    reciprocal by construction. Shaders/lib/measured.glsl computes the same.
Vec3 lookupMerlNearest(const MeasuredTable& table, const HalfDiff& hd);
Vec3 lookupMerlInterpolated(const MeasuredTable& table, const HalfDiff& hd);
Vec3 lookupMerlInterpolated(const MeasuredTable& table, const Vec3& L, const Vec3& V);

// The BRDF file every measured table renders with: BRDF() is measuredMERL()
// (shaders/lib/terms/measured_merl.glsl), which computes lookupMerlInterpolated on the device.
// No parameters; claims reciprocity and non-negativity, which the lookup guarantees.
std::string measuredBrdfText();
// That file parsed, bound to the registered measured asset `tableName`
// (BrdfDefinition::measuredTable).
Result<BrdfDefinition> measuredBrdf(const std::string& tableName);

}  // namespace brdfa
