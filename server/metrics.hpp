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
    // A frame of `method`: its render-thread time and receipt-to-reply time, in seconds.
    void count_frame(const std::string& method, double render_seconds, double total_seconds);
    void set_gpu_memory(std::uint64_t budget_bytes, std::uint64_t resident_bytes);
    void set_queue_depth(std::size_t depth);
    void set_resident_bytes(const std::string& scene, std::size_t bytes);
    void forget_scene(const std::string& scene);
    void set_connections(std::size_t connections);
    // Preview streams: how many are open, frames they sent, states superseded before a frame.
    void set_streams_active(std::size_t streams);
    void count_stream_frame();
    void count_stream_dropped(std::uint64_t states);
    // What the daemon runs on and its configured limits, exported so that alerts need no copy of them.
    void set_identity(std::string renderer, bool software, std::size_t queue_capacity, std::size_t max_clients);

    std::string prometheus_text() const;
    std::uint64_t frames() const;
    std::map<std::string, std::uint64_t> errors() const;

private:
    // Histogram buckets in seconds (Prometheus' base unit), from interactive to batch latencies.
    static constexpr std::array<double, 12> kBuckets = {0.001, 0.002, 0.005, 0.01, 0.02, 0.05,
                                                        0.1,   0.2,   0.5,   1,    5,    30};
    struct Histogram {
        std::array<std::uint64_t, kBuckets.size()> buckets{};
        std::uint64_t count = 0;
        double sum = 0.0;
        void observe(double value);
    };
    // One histogram family, a series per method.
    static void write_histograms(std::string& out, const char* name, const char* help,
                                 const std::map<std::string, Histogram>& by_method);

    mutable std::mutex mutex_;
    std::map<std::string, std::uint64_t> requests_;
    std::map<std::string, std::uint64_t> errors_;
    std::uint64_t frames_ = 0;
    std::size_t queue_depth_ = 0;
    std::size_t connections_ = 0;
    std::size_t streams_active_ = 0;
    std::uint64_t stream_frames_ = 0, stream_dropped_ = 0;
    std::map<std::string, std::size_t> resident_bytes_;
    std::map<std::string, Histogram> render_seconds_;  // by method
    std::map<std::string, Histogram> total_seconds_;
    std::uint64_t gpu_budget_bytes_ = 0, gpu_resident_bytes_ = 0;
    std::string renderer_;
    bool software_ = false;
    std::size_t queue_capacity_ = 0, max_clients_ = 0;
};

}  // namespace bounce::server
