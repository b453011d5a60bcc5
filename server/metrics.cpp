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
    for (std::size_t i = 0; i < kBucketsMs.size(); ++i) {
        if (value <= kBucketsMs[i]) ++buckets[i];
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

void Metrics::count_frame(double render_ms, double total_ms) {
    std::lock_guard lock(mutex_);
    ++frames_;
    render_ms_.observe(render_ms);
    total_ms_.observe(total_ms);
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

std::uint64_t Metrics::frames() const {
    std::lock_guard lock(mutex_);
    return frames_;
}

std::map<std::string, std::uint64_t> Metrics::errors() const {
    std::lock_guard lock(mutex_);
    return errors_;
}

void Metrics::write_histogram(std::string& out, const char* name, const char* help, const Histogram& histogram) {
    out += fmt::format("# HELP {} {}\n# TYPE {} histogram\n", name, help, name);
    for (std::size_t i = 0; i < kBucketsMs.size(); ++i) {
        out += fmt::format("{}_bucket{{le=\"{}\"}} {}\n", name, kBucketsMs[i], histogram.buckets[i]);
    }
    out += fmt::format("{}_bucket{{le=\"+Inf\"}} {}\n{}_sum {}\n{}_count {}\n", name, histogram.count, name,
                       histogram.sum, name, histogram.count);
}

std::string Metrics::prometheus_text() const {
    std::lock_guard lock(mutex_);
    std::string out;
    out += "# HELP bounce_frames_total Frames rendered and sent.\n# TYPE bounce_frames_total counter\n";
    out += fmt::format("bounce_frames_total {}\n", frames_);
    out += "# HELP bounce_requests_total Requests received, by message type.\n# TYPE bounce_requests_total counter\n";
    for (const auto& [type, count] : requests_) out += fmt::format("bounce_requests_total{{type=\"{}\"}} {}\n", escape_label(type), count);
    out += "# HELP bounce_errors_total Error replies, by code.\n# TYPE bounce_errors_total counter\n";
    for (const auto& [code, count] : errors_) out += fmt::format("bounce_errors_total{{code=\"{}\"}} {}\n", escape_label(code), count);
    out += "# HELP bounce_queue_depth Jobs waiting for the render thread.\n# TYPE bounce_queue_depth gauge\n";
    out += fmt::format("bounce_queue_depth {}\n", queue_depth_);
    out += "# HELP bounce_connections Open client connections.\n# TYPE bounce_connections gauge\n";
    out += fmt::format("bounce_connections {}\n", connections_);
    out += "# HELP bounce_resident_bytes GPU bytes a scene holds.\n# TYPE bounce_resident_bytes gauge\n";
    for (const auto& [scene, bytes] : resident_bytes_) {
        out += fmt::format("bounce_resident_bytes{{scene=\"{}\"}} {}\n", escape_label(scene), bytes);
    }
    write_histogram(out, "bounce_render_ms", "Render-thread time per frame, milliseconds.", render_ms_);
    write_histogram(out, "bounce_frame_total_ms", "Receipt to reply per frame, milliseconds.", total_ms_);
    return out;
}

}  // namespace bounce::server
