// Daemon metrics in Prometheus text format: counters, gauges and latency histograms.
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <mutex>
#include <string>

namespace bounce::server {

class Metrics {
public:
    void count_request(const std::string& type);
    void count_error(const std::string& code);
    void count_frame(double render_ms, double total_ms);
    void set_queue_depth(std::size_t depth);
    void set_resident_bytes(const std::string& scene, std::size_t bytes);
    void forget_scene(const std::string& scene);
    void set_connections(std::size_t connections);

    std::string prometheus_text() const;
    std::uint64_t frames() const;
    std::map<std::string, std::uint64_t> errors() const;

private:
    // Histogram buckets in milliseconds, from interactive to batch latencies.
    static constexpr std::array<double, 12> kBucketsMs = {1, 2, 5, 10, 20, 50, 100, 200, 500, 1000, 5000, 30000};
    struct Histogram {
        std::array<std::uint64_t, kBucketsMs.size()> buckets{};
        std::uint64_t count = 0;
        double sum = 0.0;
        void observe(double value);
    };
    static void write_histogram(std::string& out, const char* name, const char* help, const Histogram& histogram);

    mutable std::mutex mutex_;
    std::map<std::string, std::uint64_t> requests_;
    std::map<std::string, std::uint64_t> errors_;
    std::uint64_t frames_ = 0;
    std::size_t queue_depth_ = 0;
    std::size_t connections_ = 0;
    std::map<std::string, std::size_t> resident_bytes_;
    Histogram render_ms_;
    Histogram total_ms_;
};

}  // namespace bounce::server
