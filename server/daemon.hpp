// bounced: accepts clients, runs their requests on the render thread, serves ops HTTP, and shuts
// down gracefully on SIGINT/SIGTERM.
#pragma once

#include "protocol/protocol.hpp"
#include "server/metrics.hpp"
#include "server/render_service.hpp"
#include "server/request_handlers.hpp"
#include "server/scene_requests.hpp"

#include <boost/asio.hpp>

#include <atomic>
#include <chrono>
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
    std::optional<std::string> metrics_listen;  // HOST:PORT
    std::chrono::milliseconds heartbeat{15000};
    std::chrono::milliseconds drain_timeout{10000};
    std::size_t max_output_bytes = 512u << 20;  // a reader slower than this much queued output is dropped
    int network_threads = 2;
};

class Session;

class Daemon {
public:
    explicit Daemon(DaemonConfig config);
    ~Daemon();
    // Serves until SIGINT/SIGTERM (or stop()), then drains; returns the exit code.
    int run();
    void stop();

    // For sessions.
    const DaemonConfig& config() const { return config_; }
    const std::optional<std::string>& token() const { return token_; }
    protocol::Limits limits() const;
    RenderService& render_service() { return *render_; }
    Metrics& metrics() { return metrics_; }
    RequestHandlers& handlers() { return handlers_; }
    boost::asio::thread_pool& encode_pool() { return encode_pool_; }
    // CPU methods (the path-traced reference) run here, never on the render thread.
    boost::asio::thread_pool& cpu_pool() { return cpu_pool_; }
    bool try_start_cpu_job();  // false when kMaxCpuJobs are queued or running
    void finish_cpu_job() { --cpu_jobs_; }  // once for every true try_start_cpu_job()
    static constexpr int kMaxCpuJobs = 4;
    const SceneRoot& scene_root() const { return scene_root_; }
    bool shutting_down() const { return shutting_down_.load(); }
    nlohmann::json hello_body() const;
    void request_started();
    void request_finished();
    void forget(Session* session);

private:
    void accept();
    void start_metrics_server();
    void begin_shutdown();

    DaemonConfig config_;
    std::optional<std::string> token_;
    SceneRoot scene_root_;
    std::unique_ptr<RenderService> render_;
    Metrics metrics_;
    RequestHandlers handlers_{*this};
    boost::asio::io_context io_;
    boost::asio::thread_pool encode_pool_{2};
    boost::asio::thread_pool cpu_pool_{1};  // one trace at a time: it uses every core through TBB
    std::atomic<int> cpu_jobs_{0};
    boost::asio::ip::tcp::acceptor acceptor_;
    std::optional<boost::asio::ip::tcp::acceptor> metrics_acceptor_;
    boost::asio::signal_set signals_;
    boost::asio::steady_timer drain_timer_;
    std::atomic<bool> shutting_down_{false};
    std::atomic<bool> ready_{false};
    std::atomic<std::size_t> in_flight_{0};
    std::mutex sessions_mutex_;
    std::set<std::shared_ptr<Session>> sessions_;
    std::chrono::steady_clock::time_point drain_deadline_;
};

}  // namespace bounce::server
