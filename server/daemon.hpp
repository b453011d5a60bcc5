// bounced: accepts clients, runs their requests on the render thread, serves ops HTTP, and shuts
// down gracefully on SIGINT/SIGTERM.
#pragma once

#include "protocol/protocol.hpp"
#include "renderer/planning/priors.hpp"
#include "server/byte_budget.hpp"
#include "server/metrics.hpp"
#include "server/render_service.hpp"
#include "server/request_handlers.hpp"
#include "server/scene_requests.hpp"
#include "server/streams.hpp"

#include <boost/asio.hpp>

#include <atomic>
#include <chrono>
#include <deque>
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>

namespace bounce::server {

struct DaemonConfig {
    std::string listen_host = "127.0.0.1";
    std::uint16_t listen_port = 7878;
    std::optional<std::string> device;
    std::optional<std::filesystem::path> scene_root;
    std::optional<std::filesystem::path> cache_dir;
    std::optional<std::filesystem::path> token_file;
    std::optional<std::filesystem::path> port_file;  // written with the bound port (for --listen :0)
    std::size_t max_clients = 64;
    std::size_t max_message_bytes = 256u << 20;
    std::uint64_t max_pixels = 4096ull * 4096ull;
    std::size_t max_in_flight = 8;    // per connection: reading pauses while this many are pending
    std::size_t queue_capacity = 64;  // render jobs waiting across all clients
    std::optional<std::string> metrics_listen;  // HOST:PORT of the HTTP listener (--http-listen, --metrics-listen)
    bool serve_viewer = false;                  // the viewer page and /ws on it (--http-listen)
    std::chrono::milliseconds heartbeat{15000};
    std::chrono::milliseconds drain_timeout{10000};
    std::size_t max_output_bytes = 512u << 20;  // a reader slower than this much queued output is dropped
    // Request bodies held across all clients, as their bytes arrive (--max-inflight-bytes).
    std::size_t max_inflight_bytes = std::size_t{1} << 30;
    // Connections that have not authenticated yet (only with a token): their own cap, apart from
    // max_clients, the oldest closed to admit a new one; and how long they have to say hello.
    std::size_t max_unauthenticated = 16;
    std::chrono::milliseconds auth_timeout{10000};
    std::uint64_t max_scene_bytes = std::uint64_t{2} << 30;  // a scene's decoded size (--max-scene-bytes)
    std::size_t max_scenes = 64;                              // scenes resident at once (--max-scenes)
    // What every scene's GPU structures may hold together (--gpu-memory-budget); nullopt: the
    // device's default (gpu::default_memory_budget).
    std::optional<std::uint64_t> gpu_memory_budget;
    std::size_t max_ops_connections = 16;  // ops HTTP connections at once
    std::chrono::milliseconds ops_timeout{10000};  // to read an ops request and write its answer
    int network_threads = 2;
    int calibration_size = 64;  // the cost model's larger frame, pixels a side (--calibration-size)
    int calibration_change_frames = 3;  // frames timed per change (--calibration-change-frames)
    // The planner's own-error priors, measured on a deployment's own scenes (--priors; the file
    // bench/quality --priors-out writes); nullopt: the bench corpus' (OwnErrorPriors::bench).
    std::optional<std::filesystem::path> priors_file;
};

class Session;
class HttpServer;
class Transport;

class Daemon {
public:
    explicit Daemon(DaemonConfig config);
    ~Daemon();
    // Serves until SIGINT/SIGTERM (or stop()), then drains; returns the exit code.
    int run();
    void stop();

    // For sessions.
    const DaemonConfig& config() const { return config_; }
    const planning::OwnErrorPriors& priors() const { return priors_; }
    const std::optional<std::string>& token() const { return token_; }
    protocol::Limits limits() const;
    // What a frame may carry before its connection has authenticated: a `hello`, no more.
    static protocol::Limits unauthenticated_limits() { return {4096, 0}; }
    ByteBudget& inflight_bytes() { return inflight_bytes_; }
    // A session's hello succeeded: it leaves the unauthenticated count; false when max_clients
    // authenticated clients are already connected.
    bool authenticated(Session* session);
    RenderService& render_service() { return *render_; }
    boost::asio::io_context& io() { return io_; }
    Metrics& metrics() { return metrics_; }
    RequestHandlers& handlers() { return handlers_; }
    StreamHub& streams() { return streams_; }
    boost::asio::thread_pool& encode_pool() { return encode_pool_; }
    // CPU methods (the path-traced reference) run here, never on the render thread.
    boost::asio::thread_pool& cpu_pool() { return cpu_pool_; }
    // Long CPU work frames need first (bakes), off the render thread: one at a time, each uses every
    // core through TBB.
    boost::asio::thread_pool& precompute_pool() { return precompute_pool_; }
    bool try_start_cpu_job();  // false when kMaxCpuJobs are queued or running
    void finish_cpu_job() { --cpu_jobs_; }  // once for every true try_start_cpu_job()
    static constexpr int kMaxCpuJobs = 4;
    const SceneRoot& scene_root() const { return scene_root_; }
    bool shutting_down() const { return shutting_down_.load(); }
    nlohmann::json hello_body() const;
    void request_started();
    void request_finished();
    void forget(Session* session);
    // A new client connection (TCP, or a WebSocket the HTTP listener upgraded): admitted under the
    // connection caps, or closed.
    void admit(std::unique_ptr<Transport> transport);
    bool ready() const { return ready_.load(); }
    // Numbers connections in the logs (request ids read CONNECTION-REQUEST).
    std::uint64_t next_connection_number() { return ++connections_accepted_; }

private:
    void accept();
    void start_http_server();
    void begin_shutdown();

    DaemonConfig config_;
    std::optional<std::string> token_;
    planning::OwnErrorPriors priors_ = planning::OwnErrorPriors::bench();  // read at start (--priors)
    SceneRoot scene_root_;
    std::unique_ptr<RenderService> render_;
    Metrics metrics_;
    ByteBudget inflight_bytes_{config_.max_inflight_bytes};
    RequestHandlers handlers_{*this};
    StreamHub streams_{*this};
    boost::asio::io_context io_;
    std::unique_ptr<HttpServer> http_;  // after io_: closed before it
    boost::asio::thread_pool encode_pool_{2};
    boost::asio::thread_pool cpu_pool_{1};  // one trace at a time: it uses every core through TBB
    boost::asio::thread_pool precompute_pool_{1};
    std::atomic<int> cpu_jobs_{0};
    boost::asio::ip::tcp::acceptor acceptor_;
    // Every use of the acceptor after run() starts: its accept handler and its close at shutdown
    // run on several network threads, and an acceptor is not safe to use from two at once.
    boost::asio::strand<boost::asio::io_context::executor_type> accept_strand_{boost::asio::make_strand(io_)};
    boost::asio::signal_set signals_;
    boost::asio::steady_timer drain_timer_;
    std::atomic<bool> shutting_down_{false};
    std::atomic<bool> ready_{false};
    std::atomic<std::size_t> in_flight_{0};
    std::mutex sessions_mutex_;
    std::set<std::shared_ptr<Session>> sessions_;
    std::deque<std::weak_ptr<Session>> unauthenticated_;  // oldest first
    std::atomic<std::uint64_t> connections_accepted_{0};
    std::chrono::steady_clock::time_point drain_deadline_;
};

}  // namespace bounce::server
