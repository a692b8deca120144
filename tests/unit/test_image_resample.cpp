// halveRgba8: the preview frames' 2x2 box filter.
#include <gtest/gtest.h>

#include <vector>

#include "brdfa/image_resample.h"

namespace brdfa {
namespace {

TEST(HalveRgba8, AveragesEachTwoByTwoBlockWithRounding) {
  // 4x2 -> 2x1. Block 0: red 0,1,2,3 -> 1.5 rounds to 2; block 1: 10,20,30,41 -> 25.25 -> 25.
  std::vector<uint8_t> px(4 * 2 * 4, 255);
  const uint8_t reds[2][4] = {{0, 1, 10, 20}, {2, 3, 30, 41}};
  for (int y = 0; y < 2; ++y)
    for (int x = 0; x < 4; ++x) px[(y * 4 + x) * 4] = reds[y][x];
  int w = -1, h = -1;
  std::vector<uint8_t> out = halveRgba8(px.data(), 4, 2, w, h);
  ASSERT_EQ(w, 2);
  ASSERT_EQ(h, 1);
  ASSERT_EQ(out.size(), 8u);
  EXPECT_EQ(out[0], 2);
  EXPECT_EQ(out[4], 25);
  EXPECT_EQ(out[1], 255);  // other channels untouched by the averaging of equal values
  EXPECT_EQ(out[7], 255);
}

TEST(HalveRgba8, DropsAnOddLastRowAndColumn) {
  std::vector<uint8_t> px(5 * 3 * 4);
  for (size_t i = 0; i < px.size(); ++i) px[i] = uint8_t(i % 4 == 0 ? 100 : 0);
  for (int x = 0; x < 5; ++x) px[(2 * 5 + x) * 4] = 0;  // last row: would pull the mean down
  for (int y = 0; y < 3; ++y) px[(y * 5 + 4) * 4] = 0;  // last column too
  int w = 0, h = 0;
  std::vector<uint8_t> out = halveRgba8(px.data(), 5, 3, w, h);
  ASSERT_EQ(w, 2);
  ASSERT_EQ(h, 1);
  EXPECT_EQ(out[0], 100);
  EXPECT_EQ(out[4], 100);
}

TEST(HalveRgba8, TooSmallOrNullGivesNothing) {
  std::vector<uint8_t> px(4 * 4, 7);
  int w = 9, h = 9;
  EXPECT_TRUE(halveRgba8(px.data(), 1, 4, w, h).empty());
  EXPECT_EQ(w, 0);
  EXPECT_EQ(h, 0);
  EXPECT_TRUE(halveRgba8(nullptr, 4, 4, w, h).empty());
}

}  // namespace
}  // namespace brdfa
