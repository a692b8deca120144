// MERL tables: reading and validation, MERL's bin lookup and the interpolated lookup, on files
// made in MERL's layout from known functions (tests/support/merl_files.h).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>

#include "brdfa/measured.h"
#include "merl_files.h"

namespace brdfa {
namespace {

using testsupport::Dir;
using testsupport::Rgb;

constexpr double kPi = 3.14159265358979323846;

// The bin coordinate of each axis at fraction `t` of bin `b` (0: lower edge, 1/2: centre).
HalfDiff atFraction(const MerlBin& b, double th, double td, double tp) {
  const double u = (b.thetaH + th) / kMerlThetaHBins;
  return HalfDiff{u * u * kPi / 2, (b.thetaD + td) / kMerlThetaDBins * kPi / 2, (b.phiD + tp) / kMerlPhiDBins * kPi};
}

// The bin a pair of directions made from `hd` falls in, as MERL's reader finds it.
MerlBin binThroughDirections(const HalfDiff& hd) {
  Dir L, V;
  directionsFromHalfDiff(hd, L, V);
  return merlBinOf(halfDiffFromDirections(L, V));
}

bool sameBin(const MerlBin& a, const MerlBin& b) {
  return a.thetaH == b.thetaH && a.thetaD == b.thetaD && a.phiD == b.phiD;
}

const MeasuredTable& indexTable() {
  static const MeasuredTable table = [] {
    auto read = readMerl(writeMerl(testsupport::indexPlanar()));
    EXPECT_TRUE(read) << read.error().message;
    return read ? std::move(read.value()) : MeasuredTable{};
  }();
  return table;
}

TEST(MeasuredTable, IndexFileReadsBackEveryBinInItsChannelOrder) {
  const MeasuredTable& t = indexTable();
  ASSERT_EQ(t.rgb.size(), 3 * kMerlBins);
  EXPECT_EQ(t.validBins, kMerlBins);
  for (size_t i = 0; i < kMerlBins; ++i)
    for (int c = 0; c < 3; ++c)
      ASSERT_EQ(t.rgb[3 * i + c], float((double(i) + 0.25 * c) * kMerlScale[c])) << "bin " << i << " channel " << c;
}

TEST(MeasuredTable, EveryBinIsFoundAtItsCentreAndInsideEachEdge) {
  const MeasuredTable& t = indexTable();
  // A thousandth of a bin inside each edge of each axis, the other axes at their centres.
  const double in = 1e-3;
  size_t checked = 0;
  for (int h = 0; h < kMerlThetaHBins; ++h)
    for (int d = 0; d < kMerlThetaDBins; ++d)
      for (int p = 0; p < kMerlPhiDBins; ++p) {
        const MerlBin b{h, d, p};
        const size_t i = merlIndex(b);
        const HalfDiff centre = merlBinCentre(b);
        ASSERT_TRUE(sameBin(merlBinOf(centre), b)) << "centre of bin " << i;
        ASSERT_TRUE(sameBin(binThroughDirections(centre), b)) << "centre of bin " << i << " through L and V";
        const Vec3 exact = lookupMerlInterpolated(t, centre);
        for (int c = 0; c < 3; ++c)
          ASSERT_EQ(exact[c], t.rgb[3 * i + c]) << "interpolated lookup at the centre of bin " << i;
        const HalfDiff edges[6] = {atFraction(b, in, 0.5, 0.5), atFraction(b, 1 - in, 0.5, 0.5),
                                   atFraction(b, 0.5, in, 0.5), atFraction(b, 0.5, 1 - in, 0.5),
                                   atFraction(b, 0.5, 0.5, in), atFraction(b, 0.5, 0.5, 1 - in)};
        for (const HalfDiff& e : edges) {
          ASSERT_TRUE(sameBin(binThroughDirections(e), b)) << "an edge of bin " << i;
          ASSERT_EQ(lookupMerlNearest(t, e)[0], t.rgb[3 * i]) << "an edge of bin " << i;
        }
        ++checked;
      }
  EXPECT_EQ(checked, kMerlBins);
}

TEST(MeasuredTable, HalfDiffAnglesRoundTripThroughDirections) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int k = 0; k < 10000; ++k) {
    const HalfDiff hd{u(rng) * kPi / 2, u(rng) * kPi / 2, u(rng) * kPi};
    Dir L, V;
    directionsFromHalfDiff(hd, L, V);
    EXPECT_NEAR(L[0] * L[0] + L[1] * L[1] + L[2] * L[2], 1.0, 1e-12);
    EXPECT_NEAR(V[0] * V[0] + V[1] * V[1] + V[2] * V[2], 1.0, 1e-12);
    const HalfDiff back = halfDiffFromDirections(L, V);
    EXPECT_NEAR(back.thetaH, hd.thetaH, 1e-7);
    EXPECT_NEAR(back.thetaD, hd.thetaD, 1e-7);
    // phi_d is periodic with period pi.
    const double dp = std::remainder(back.phiD - hd.phiD, kPi);
    EXPECT_NEAR(dp, 0.0, 1e-6) << hd.thetaH << " " << hd.thetaD << " " << hd.phiD;
  }
}

// Directions above the horizon about an arbitrary normal's local frame, some grazing.
std::vector<std::pair<Vec3, Vec3>> randomPairs(int n, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  auto dir = [&] {
    const double z = std::max(1e-3, u(rng)), phi = 2 * kPi * u(rng), s = std::sqrt(1 - z * z);
    return Vec3{float(s * std::cos(phi)), float(s * std::sin(phi)), float(z)};
  };
  std::vector<std::pair<Vec3, Vec3>> pairs;
  for (int k = 0; k < n; ++k) pairs.push_back({dir(), dir()});
  return pairs;
}

TEST(MeasuredTable, InterpolatedLookupIsReciprocal) {
  auto read = readMerl(testsupport::ggxMerl(0.3, {0.9, 0.6, 0.5}));
  ASSERT_TRUE(read) << read.error().message;
  for (const auto& [L, V] : randomPairs(20000, 3)) {
    const Vec3 a = lookupMerlInterpolated(*read, L, V), b = lookupMerlInterpolated(*read, V, L);
    for (int c = 0; c < 3; ++c) ASSERT_NEAR(a[c], b[c], 1e-5 * std::max(1.0f, std::abs(a[c])));
  }
}

TEST(MeasuredTable, LambertTableIsItsConstantEverywhereEvenWithBinsMissing) {
  const Rgb rho{0.8, 0.5, 0.2};
  std::vector<double> planar = testsupport::merlPlanar([&](const Dir&, const Dir&) {
    return Rgb{rho[0] / kPi, rho[1] / kPi, rho[2] / kPi};
  });
  // Every seventh bin without data (in one channel only: the whole bin counts as missing).
  size_t missing = 0;
  for (size_t i = 0; i < kMerlBins; i += 7, ++missing) planar[(i % 3) * kMerlBins + i] = -1.0;
  auto read = readMerl(writeMerl(planar));
  ASSERT_TRUE(read) << read.error().message;
  EXPECT_EQ(read->validBins, kMerlBins - missing);
  EXPECT_FALSE(read->valid(0));
  EXPECT_TRUE(read->valid(1));
  for (const auto& [L, V] : randomPairs(20000, 5)) {
    const Vec3 f = lookupMerlInterpolated(*read, L, V);
    for (int c = 0; c < 3; ++c) ASSERT_NEAR(f[c], rho[c] / kPi, 1e-6);
  }
  // MERL's own lookup in a bin without data: 0.
  EXPECT_EQ(lookupMerlNearest(*read, merlBinCentre(MerlBin{0, 0, 0}))[1], 0.0f);
}

// The interpolated table against the function it was made from, over directions weighted by
// both cosines: the relative RMS error of f, a few percent for a glossy lobe.
double relativeRmsAgainstGgx(double alpha, int n) {
  const Rgb f0{0.95, 0.64, 0.54};
  auto read = readMerl(testsupport::ggxMerl(alpha, f0));
  EXPECT_TRUE(read);
  if (!read) return INFINITY;
  double err = 0, ref = 0;
  for (const auto& [L, V] : randomPairs(n, 11)) {
    const Rgb truth = testsupport::ggxValue({L[0], L[1], L[2]}, {V[0], V[1], V[2]}, alpha, f0);
    const Vec3 f = lookupMerlInterpolated(*read, L, V);
    const double w = L[2] * V[2];
    err += w * (f[1] - truth[1]) * (f[1] - truth[1]);
    ref += w * truth[1] * truth[1];
  }
  return std::sqrt(err / ref);
}

TEST(MeasuredTable, GgxTableFollowsTheAnalyticGgxWithinInterpolationError) {
  EXPECT_LT(relativeRmsAgainstGgx(0.5, 50000), 0.01);
  EXPECT_LT(relativeRmsAgainstGgx(0.2, 50000), 0.012);
  EXPECT_LT(relativeRmsAgainstGgx(0.05, 50000), 0.025);
}

TEST(MeasuredTable, LobeFitFindsTheGgxWidthAndLeavesADiffuseTableToTheCosine) {
  for (double alpha : {0.05, 0.1, 0.3, 0.5}) {
    auto read = readMerl(testsupport::ggxMerl(alpha, {0.9, 0.9, 0.9}));
    ASSERT_TRUE(read) << read.error().message;
    EXPECT_NEAR(read->lobeAlpha, alpha, 0.2 * alpha) << "alpha " << alpha;
    EXPECT_GE(read->lobeWeight, 0.6f) << "alpha " << alpha;  // no diffuse floor: mostly the lobe
  }
  auto diffuse = readMerl(testsupport::lambertMerl({0.5, 0.5, 0.5}));
  ASSERT_TRUE(diffuse);
  EXPECT_FLOAT_EQ(diffuse->lobeWeight, 0.1f);
  // GGX 0.2 (F0 0.5) over a Lambertian of albedo 0.5: about as much energy in each part.
  auto mixed = readMerl(testsupport::merlFile([](const testsupport::Dir& L, const testsupport::Dir& V) {
    if (L[2] <= 0 || V[2] <= 0) return Rgb{-1, -1, -1};
    const Rgb s = testsupport::ggxValue(L, V, 0.2, {0.5, 0.5, 0.5});
    return Rgb{s[0] + 0.5 / kPi, s[1] + 0.5 / kPi, s[2] + 0.5 / kPi};
  }));
  ASSERT_TRUE(mixed);
  EXPECT_NEAR(mixed->lobeAlpha, 0.2, 0.05);
  EXPECT_GT(mixed->lobeWeight, 0.25f);
  EXPECT_LT(mixed->lobeWeight, 0.75f);
}

TEST(MeasuredTable, RefusesWrongSizesAndHeaders) {
  const std::string good = testsupport::lambertMerl({0.5, 0.5, 0.5});
  ASSERT_TRUE(readMerl(good));
  EXPECT_TRUE(hasMerlHeader(good));
  auto refused = [](const std::string& bytes, const std::string& words) {
    auto r = readMerl(bytes);
    if (r) return ::testing::AssertionFailure() << "accepted";
    if (r.error().code != ErrorCode::InvalidArgument) return ::testing::AssertionFailure() << "not InvalidArgument";
    if (r.error().message.find(words) == std::string::npos)
      return ::testing::AssertionFailure() << "message '" << r.error().message << "' lacks '" << words << "'";
    return ::testing::AssertionSuccess();
  };
  EXPECT_TRUE(refused("", "this file is 0 bytes"));
  EXPECT_TRUE(refused(good.substr(0, 12), "truncated"));
  EXPECT_TRUE(refused(good.substr(0, good.size() - 1), "truncated"));
  EXPECT_TRUE(refused(good + "x", "bytes after the table"));
  std::string header = good;
  const int32_t wrong[3] = {90, 90, 360};  // the full phi_d range: not MERL's layout
  std::memcpy(header.data(), wrong, sizeof wrong);
  EXPECT_FALSE(hasMerlHeader(header));
  EXPECT_TRUE(refused(header, "90 x 90 x 360 bins"));
}

TEST(MeasuredTable, RefusesNanInfinityAndATableWithoutData) {
  std::vector<double> planar = testsupport::indexPlanar();
  const MerlBin bin{3, 4, 5};
  planar[1 * kMerlBins + merlIndex(bin)] = std::nan("");
  auto nan = readMerl(writeMerl(planar));
  ASSERT_FALSE(nan);
  EXPECT_NE(nan.error().message.find("NaN in the green channel of bin (theta_h 3, theta_d 4, phi_d 5)"),
            std::string::npos)
      << nan.error().message;
  planar[1 * kMerlBins + merlIndex(bin)] = 1.0;
  planar[2 * kMerlBins + 17] = INFINITY;
  auto inf = readMerl(writeMerl(planar));
  ASSERT_FALSE(inf);
  EXPECT_NE(inf.error().message.find("infinite value in the blue channel"), std::string::npos);
  auto none = readMerl(writeMerl(std::vector<double>(3 * kMerlBins, -1.0)));
  ASSERT_FALSE(none);
  EXPECT_NE(none.error().message.find("no bin with data"), std::string::npos);
}

}  // namespace
}  // namespace brdfa
