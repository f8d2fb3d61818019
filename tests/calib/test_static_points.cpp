// static_points.csv reader (tools/calib/static_points.hpp): accepted rows and
// a file:line: reason for every malformed one.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "tools/calib/static_points.hpp"

namespace uwbnav::calib {
namespace {

const std::string kHeader = "point_id,t_start_s,t_end_s,x_m,y_m,z_m,yaw_deg\n";

TEST(StaticPoints, RowsWithAndWithoutHeadingAreRead) {
  std::vector<StaticPoint> pts;
  std::vector<std::string> errors;
  ASSERT_EQ(parse_static_points("# surveyed 2024-05-02\n" + kHeader + "P1,10,40,3.2,1.5,0,90\r\nP2, 50.5 ,80,6.1,1.5,0.02,\n",
                                "sp.csv", pts, errors),
            Status::kOk)
      << (errors.empty() ? "" : errors[0]);
  ASSERT_EQ(pts.size(), 2U);
  EXPECT_EQ(pts[0].id, "P1");
  EXPECT_EQ(pts[0].t_start_us, 10000000U);
  EXPECT_EQ(pts[0].t_end_us, 40000000U);
  EXPECT_TRUE(pts[0].has_yaw);
  EXPECT_NEAR(pts[0].yaw_rad, M_PI / 2, 1e-12);
  EXPECT_EQ(pts[1].t_start_us, 50500000U);
  EXPECT_FALSE(pts[1].has_yaw);
  EXPECT_DOUBLE_EQ(pts[1].pos_nav_m[2], 0.02);
}

TEST(StaticPoints, MalformedRowsAreRefusedWithFileLineAndReason) {
  struct Case {
    std::string text;
    std::string message;
  };
  const std::vector<Case> cases = {
      {"point,t0,t1\n", "sp.csv:1: header must be"},
      {"", "no header line"},
      {kHeader, "sp.csv:1: no static point rows"},
      {kHeader + "P1,10,40,3.2,1.5,0\n", "sp.csv:2: 6 cells, expected 7"},
      {kHeader + ",10,40,3.2,1.5,0,\n", "sp.csv:2: empty point_id"},
      {kHeader + "P1,ten,40,3.2,1.5,0,\n", "sp.csv:2: t_start_s 'ten' is not a finite number"},
      {kHeader + "P1,10,40,nan,1.5,0,\n", "sp.csv:2: x_m 'nan' is not a finite number"},
      {kHeader + "P1,10,40,3,1.5,0,north\n", "sp.csv:2: yaw_deg 'north' is not a finite number"},
      {kHeader + "P1,40,10,3,1.5,0,\n", "sp.csv:2: window [40, 10] s is empty or negative"},
      {kHeader + "P1,-1,10,3,1.5,0,\n", "sp.csv:2: window [-1, 10] s is empty or negative"},
      {kHeader + "P1,10,40,3,1.5,0,\nP2,30,60,5,1.5,0,\n", "sp.csv:3: window of point P2 overlaps point P1 (line 2)"},
  };
  for (const Case& c : cases) {
    std::vector<StaticPoint> pts;
    std::vector<std::string> errors;
    EXPECT_EQ(parse_static_points(c.text, "sp.csv", pts, errors), Status::kInvalidArgument) << c.text;
    bool found = false;
    for (const auto& e : errors) found = found || e.find(c.message) != std::string::npos;
    EXPECT_TRUE(found) << c.text << " -> " << (errors.empty() ? "(none)" : errors[0]);
  }
  std::vector<StaticPoint> pts;
  std::vector<std::string> errors;
  EXPECT_EQ(read_static_points("/nonexistent/static_points.csv", pts, errors), Status::kNotFound);
}

}  // namespace
}  // namespace uwbnav::calib
