// The /metrics text: label values a client chose (scene names) are escaped as the Prometheus text
// format requires, so no name can end its label or forge a line.
#include "server/metrics.hpp"

#include <gtest/gtest.h>

#include <sstream>

namespace bounce::server {
namespace {

TEST(PrometheusText, LabelValuesAreEscaped) {
    Metrics metrics;
    const std::string evil = "evil\"} 1\nbounce_fake_total{a=\"\\";
    metrics.set_resident_bytes(evil, 42);
    const std::string text = metrics.prometheus_text();
    std::istringstream lines(text);
    std::string line;
    bool found = false;
    while (std::getline(lines, line)) {
        EXPECT_NE(line.rfind("bounce_fake_total", 0), 0u) << "a forged line: " << line;
        if (line.rfind("bounce_resident_bytes{", 0) == 0) {
            EXPECT_EQ(line, "bounce_resident_bytes{scene=\"evil\\\"} 1\\nbounce_fake_total{a=\\\"\\\\\"} 42");
            found = true;
        }
    }
    EXPECT_TRUE(found) << text;
}

// Latencies in seconds (Prometheus' base unit), a series per method; the build's version and
// renderer as labels; the queue and client limits, so alerts need no copy of the flags.
TEST(PrometheusText, FrameTimesAreSecondsByMethodAndTheBuildIsNamed) {
    Metrics metrics;
    metrics.set_identity("llvmpipe (LLVM 15.0.6, 256 bits)", true, 64, 32);
    metrics.count_frame("vct", 0.004, 0.03);
    metrics.count_frame("reference", 2.0, 2.5);
    const std::string text = metrics.prometheus_text();
    for (const std::string expected :
         {"bounce_build_info{version=\"" BOUNCE_VERSION "\",renderer=\"llvmpipe (LLVM 15.0.6, 256 bits)\",software=\"true\"} 1\n",
          "bounce_queue_capacity 64\n", "bounce_max_clients 32\n", "# TYPE bounce_render_seconds histogram\n",
          "bounce_render_seconds_bucket{method=\"vct\",le=\"0.002\"} 0\n",
          "bounce_render_seconds_bucket{method=\"vct\",le=\"0.005\"} 1\n",
          "bounce_render_seconds_bucket{method=\"reference\",le=\"1\"} 0\n",
          "bounce_render_seconds_bucket{method=\"reference\",le=\"5\"} 1\n",
          "bounce_frame_seconds_bucket{method=\"vct\",le=\"0.05\"} 1\n", "bounce_frame_seconds_count{method=\"reference\"} 1\n",
          "bounce_frame_seconds_sum{method=\"reference\"} 2.5\n"}) {
        EXPECT_NE(text.find(expected), std::string::npos) << expected << " not in:\n" << text;
    }
    EXPECT_EQ(text.find("_ms"), std::string::npos) << "a metric in milliseconds";
}

}  // namespace
}  // namespace bounce::server
