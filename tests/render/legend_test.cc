// The shared plot legend: the corner it takes (free of data, then of decoration, in the
// order top right, top left, bottom right, bottom left), outside on the right otherwise.
#include "render/legend.h"

#include <gtest/gtest.h>

#include <cmath>

#include "render/plot_style.h"

namespace twinsim::plot_style {
namespace {

const Rect kArea{100, 50, 500, 350};  // px
const LegendSize kSize{120, 60};       // px

TEST(Legend, TakesTheTopRightCornerOfAnEmptyArea) {
  const Occupancy empty(kArea);
  const std::optional<Rect> box = LegendCorner(kArea, kSize, empty);
  ASSERT_TRUE(box);
  EXPECT_DOUBLE_EQ(box->x1, kArea.x1 - kLegendInset);
  EXPECT_DOUBLE_EQ(box->y0, kArea.y0 + kLegendInset);
  EXPECT_DOUBLE_EQ(box->width(), kSize.width);
  EXPECT_DOUBLE_EQ(box->height(), kSize.height);
}

TEST(Legend, AvoidsDataThenDecorationAndGoesOutsideWhenEveryCornerHasData) {
  Occupancy data(kArea);
  data.MarkSegment({480, 60}, {490, 70}, 2);  // top right
  std::optional<Rect> box = LegendCorner(kArea, kSize, data);
  ASSERT_TRUE(box);
  EXPECT_DOUBLE_EQ(box->x0, kArea.x0 + kLegendInset);  // top left
  EXPECT_DOUBLE_EQ(box->y0, kArea.y0 + kLegendInset);

  Occupancy decoration(kArea);
  decoration.MarkRect(Rect{110, 60, 130, 70});  // top left
  box = LegendCorner(kArea, kSize, data, &decoration);
  ASSERT_TRUE(box);
  EXPECT_DOUBLE_EQ(box->x1, kArea.x1 - kLegendInset);  // bottom right
  EXPECT_DOUBLE_EQ(box->y1, kArea.y1 - kLegendInset);

  data.MarkDisc({120, 65}, 3);
  data.MarkDisc({480, 330}, 3);
  data.MarkDisc({120, 330}, 3);
  EXPECT_FALSE(LegendCorner(kArea, kSize, data));
  EXPECT_FALSE(LegendCorner(kArea, LegendSize{400, 60}, Occupancy(kArea)));  // fits no corner

  const Rect right = LegendRight(kArea, kSize);
  EXPECT_DOUBLE_EQ(right.x0, kArea.x1 + kLegendGap);
  EXPECT_DOUBLE_EQ(right.y0, kArea.y0);
  EXPECT_DOUBLE_EQ(right.width(), kSize.width);
}

TEST(Legend, OccupancyIgnoresWhatLiesOutsideOrIsNotFinite) {
  Occupancy occ(kArea);
  occ.MarkSegment({0, 0}, {50, 20}, 2);     // wholly outside
  occ.MarkDisc({NAN, 200}, 5);
  occ.MarkSegment({200, 200}, {INFINITY, 200}, 2);
  EXPECT_EQ(occ.Count(kArea), 0);
  occ.MarkSegment({200, 200}, {240, 200}, 1);
  EXPECT_GT(occ.Count(Rect{195, 195, 245, 205}), 0);
  EXPECT_EQ(occ.Count(Rect{300, 300, 320, 320}), 0);
  EXPECT_EQ(MeasureLegend({}).width, 0);
}

}  // namespace
}  // namespace twinsim::plot_style
