#include "server/metrics.hpp"

#include <fmt/format.h>

namespace bounce::server {
namespace {

// A label value as the Prometheus text format writes it: backslash, double quote and newline
// escaped, so a client-chosen name (a scene's) can never end the label or the line.
std::string escape_label(std::string_view value) {
    std::string escaped;
    escaped.reserve(value.size());
    for (const char c : value) {
        if (c == '\\') escaped += "\\\\";
        else if (c == '"') escaped += "\\\"";
        else if (c == '\n') escaped += "\\n";
        else escaped += c;
    }
    return escaped;
}

}  // namespace

void Metrics::Histogram::observe(double value) {
    for (std::size_t i = 0; i < kBuckets.size(); ++i) {
        if (value <= kBuckets[i]) ++buckets[i];
    }
    ++count;
    sum += value;
}

void Metrics::count_request(const std::string& type) {
    std::lock_guard lock(mutex_);
    ++requests_[type];
}

void Metrics::count_error(const std::string& code) {
    std::lock_guard lock(mutex_);
    ++errors_[code];
}

void Metrics::count_frame(const std::string& method, double render_seconds, double total_seconds) {
    std::lock_guard lock(mutex_);
    ++frames_;
    render_seconds_[method].observe(render_seconds);
    total_seconds_[method].observe(total_seconds);
}

void Metrics::set_gpu_memory(std::uint64_t budget_bytes, std::uint64_t resident_bytes) {
    std::lock_guard lock(mutex_);
    gpu_budget_bytes_ = budget_bytes;
    gpu_resident_bytes_ = resident_bytes;
}

void Metrics::set_queue_depth(std::size_t depth) {
    std::lock_guard lock(mutex_);
    queue_depth_ = depth;
}

void Metrics::set_resident_bytes(const std::string& scene, std::size_t bytes) {
    std::lock_guard lock(mutex_);
    resident_bytes_[scene] = bytes;
}

void Metrics::forget_scene(const std::string& scene) {
    std::lock_guard lock(mutex_);
    resident_bytes_.erase(scene);
}

void Metrics::set_connections(std::size_t connections) {
    std::lock_guard lock(mutex_);
    connections_ = connections;
}

void Metrics::set_streams_active(std::size_t streams) {
    std::lock_guard lock(mutex_);
    streams_active_ = streams;
}

void Metrics::count_stream_frame() {
    std::lock_guard lock(mutex_);
    ++stream_frames_;
}

void Metrics::count_stream_dropped(std::uint64_t states) {
    std::lock_guard lock(mutex_);
    stream_dropped_ += states;
}

std::uint64_t Metrics::frames() const {
    std::lock_guard lock(mutex_);
    return frames_;
}

std::map<std::string, std::uint64_t> Metrics::errors() const {
    std::lock_guard lock(mutex_);
    return errors_;
}

void Metrics::write_histograms(std::string& out, const char* name, const char* help,
                               const std::map<std::string, Histogram>& by_method) {
    out += fmt::format("# HELP {} {}\n# TYPE {} histogram\n", name, help, name);
    for (const auto& [method, histogram] : by_method) {
        const std::string label = escape_label(method);
        for (std::size_t i = 0; i < kBuckets.size(); ++i) {
            out += fmt::format("{}_bucket{{method=\"{}\",le=\"{}\"}} {}\n", name, label, kBuckets[i], histogram.buckets[i]);
        }
        out += fmt::format("{}_bucket{{method=\"{}\",le=\"+Inf\"}} {}\n{}_sum{{method=\"{}\"}} {}\n{}_count{{method=\"{}\"}} {}\n",
                           name, label, histogram.count, name, label, histogram.sum, name, label, histogram.count);
    }
}

void Metrics::set_identity(std::string renderer, bool software, std::size_t queue_capacity, std::size_t max_clients) {
    std::lock_guard lock(mutex_);
    renderer_ = std::move(renderer);
    software_ = software;
    queue_capacity_ = queue_capacity;
    max_clients_ = max_clients;
}

std::string Metrics::prometheus_text() const {
    std::lock_guard lock(mutex_);
    std::string out;
    // A metric of one unlabelled sample: its HELP, its TYPE and its value.
    const auto scalar = [&out](std::string_view name, std::string_view type, std::string_view help, auto value) {
        out += fmt::format("# HELP {0} {1}\n# TYPE {0} {2}\n{0} {3}\n", name, help, type, value);
    };
    out += "# HELP bounce_build_info The daemon's version and the renderer it runs on.\n# TYPE bounce_build_info gauge\n";
    out += fmt::format("bounce_build_info{{version=\"{}\",renderer=\"{}\",software=\"{}\"}} 1\n", BOUNCE_VERSION,
                       escape_label(renderer_), software_ ? "true" : "false");
    scalar("bounce_queue_capacity", "gauge", "Render jobs that may wait (--queue); past it requests get busy.", queue_capacity_);
    scalar("bounce_max_clients", "gauge", "Connections the daemon accepts (--max-clients).", max_clients_);
    scalar("bounce_gpu_memory_budget_bytes", "gauge", "What every scene's GPU structures may hold (--gpu-memory-budget).", gpu_budget_bytes_);
    scalar("bounce_gpu_resident_bytes", "gauge", "What every scene's GPU structures hold, after the last frame.", gpu_resident_bytes_);
    scalar("bounce_frames_total", "counter", "Frames rendered and sent.", frames_);
    out += "# HELP bounce_requests_total Requests received, by message type.\n# TYPE bounce_requests_total counter\n";
    for (const auto& [type, count] : requests_) out += fmt::format("bounce_requests_total{{type=\"{}\"}} {}\n", escape_label(type), count);
    out += "# HELP bounce_errors_total Error replies, by code.\n# TYPE bounce_errors_total counter\n";
    for (const auto& [code, count] : errors_) out += fmt::format("bounce_errors_total{{code=\"{}\"}} {}\n", escape_label(code), count);
    scalar("bounce_queue_depth", "gauge", "Jobs waiting for the render thread.", queue_depth_);
    scalar("bounce_connections", "gauge", "Open client connections.", connections_);
    scalar("bounce_streams_active", "gauge", "Open preview streams.", streams_active_);
    scalar("bounce_stream_frames_total", "counter", "Frames preview streams sent.", stream_frames_);
    scalar("bounce_stream_dropped_stale_total", "counter", "Stream states superseded before a frame of them started.", stream_dropped_);
    out += "# HELP bounce_resident_bytes GPU bytes a scene holds.\n# TYPE bounce_resident_bytes gauge\n";
    for (const auto& [scene, bytes] : resident_bytes_) {
        out += fmt::format("bounce_resident_bytes{{scene=\"{}\"}} {}\n", escape_label(scene), bytes);
    }
    write_histograms(out, "bounce_render_seconds", "Render time per frame (render thread or CPU pool), seconds.",
                     render_seconds_);
    write_histograms(out, "bounce_frame_seconds", "Receipt to reply per frame, seconds.", total_seconds_);
    return out;
}

}  // namespace bounce::server
