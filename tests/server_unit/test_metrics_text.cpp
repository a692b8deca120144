// GET /metrics' writer and counters: the exposition format's rules that a scraper
// depends on, checked line by line; the topology test parses the real endpoint with a
// Prometheus parser.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <sstream>

#include "metrics/metrics.h"
#include "metrics/prometheus_text.h"

namespace brdfa::server {
namespace {

std::vector<std::string> lines(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string l; std::getline(in, l);) out.push_back(l);
  return out;
}

TEST(PrometheusText, FamilyHeadersSamplesAndEscapedLabels) {
  PrometheusText t;
  t.family("brdfa_x_total", "counter", "A help\\text\nwith a newline");
  t.sample("brdfa_x_total", 3, {{"reason", "a\"b\\c\nd"}});
  t.sample("brdfa_x_total", 0.25);
  t.sample("brdfa_x_total", std::numeric_limits<double>::infinity());
  t.sample("brdfa_x_total", std::nan(""));
  EXPECT_EQ(lines(t.text()), (std::vector<std::string>{
                                 "# HELP brdfa_x_total A help\\\\text\\nwith a newline",
                                 "# TYPE brdfa_x_total counter",
                                 "brdfa_x_total{reason=\"a\\\"b\\\\c\\nd\"} 3",
                                 "brdfa_x_total 0.25",
                                 "brdfa_x_total +Inf",
                                 "brdfa_x_total NaN",
                             }));
}

TEST(PrometheusText, HistogramBucketsAreCumulativeAndEndAtInf) {
  DurationHistogram h;
  for (double s : {0.0005, 0.001, 0.002, 0.3, 7.0, 60.0}) h.add(s);
  PrometheusText t;
  t.family("brdfa_d_seconds", "histogram", "d");
  t.histogram("brdfa_d_seconds", h, {{"queue", "render"}});
  auto l = lines(t.text());
  ASSERT_EQ(l.size(), 2 + DurationHistogram::kBoundsSec.size() + 1 + 2);
  EXPECT_EQ(l[2], "brdfa_d_seconds_bucket{queue=\"render\",le=\"0.001\"} 2");  // le is inclusive
  EXPECT_EQ(l[3], "brdfa_d_seconds_bucket{queue=\"render\",le=\"0.0025\"} 3");
  EXPECT_EQ(l[2 + 8], "brdfa_d_seconds_bucket{queue=\"render\",le=\"0.5\"} 4");
  EXPECT_EQ(l[2 + 12], "brdfa_d_seconds_bucket{queue=\"render\",le=\"10\"} 5");
  EXPECT_EQ(l[2 + 13], "brdfa_d_seconds_bucket{queue=\"render\",le=\"+Inf\"} 6");
  const std::string sumPrefix = "brdfa_d_seconds_sum{queue=\"render\"} ";
  ASSERT_EQ(l[2 + 14].rfind(sumPrefix, 0), 0u) << l[2 + 14];
  EXPECT_NEAR(std::stod(l[2 + 14].substr(sumPrefix.size())), 67.3035, 1e-12);
  EXPECT_EQ(l[2 + 15], "brdfa_d_seconds_count{queue=\"render\"} 6");
}

TEST(DurationHistogram, MergeAddsAndNaNCountsWithoutPoisoningTheSum) {
  DurationHistogram a, b;
  a.add(0.01);
  b.add(0.01);
  b.add(std::nan(""));
  a.merge(b);
  EXPECT_EQ(a.count, 3u);
  EXPECT_DOUBLE_EQ(a.sumSec, 0.02);
  EXPECT_EQ(a.counts[3], 2u);  // (0.005, 0.01]
  EXPECT_EQ(a.counts.back(), 1u);
}

TEST(ServiceMetrics, ErrorsCountByReasonAndEveryResponseByStatus) {
  ServiceMetrics m;
  m.countResponse(200, "");
  m.countResponse(404, "not_found");
  m.countResponse(404, "not_found");
  m.countResponse(503, "draining");
  m.countResponse(413, "");  // no JSON error name: named by status
  EXPECT_EQ(m.rejectionsByReason(),
            (std::map<std::string, uint64_t>{{"draining", 1}, {"http_413", 1}, {"not_found", 2}}));
  EXPECT_EQ(m.responsesByStatus(), (std::map<int, uint64_t>{{200, 1}, {404, 2}, {413, 1}, {503, 1}}));
}

}  // namespace
}  // namespace brdfa::server
