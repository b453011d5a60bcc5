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

}  // namespace
}  // namespace bounce::server
