#include "server/daemon.hpp"

#include <boost/asio/bind_executor.hpp>
#include <boost/asio/dispatch.hpp>

#include "renderer/base/bytes.hpp"
#include "renderer/base/error.hpp"
#include "renderer/base/log.hpp"
#include "renderer/scene/builtin.hpp"
#include "server/http_server.hpp"
#include "server/session.hpp"


#include <cstdlib>
#include <fstream>
#include <thread>

namespace bounce::server {
namespace {

namespace asio = boost::asio;
using asio::ip::tcp;

bool is_loopback(const std::string& host) {
    boost::system::error_code error;
    const auto address = asio::ip::make_address(host, error);
    return host == "localhost" || (!error && address.is_loopback());
}

std::string read_token(const std::filesystem::path& path) {
    std::string token;
    try {
        token = protocol::read_token_file(path.string());
    } catch (const std::exception& error) {
        throw InputError(fmt::format("--token-file: {}", error.what()));
    }
    if (token.size() < 16) throw InputError(fmt::format("--token-file {}: the token has fewer than 16 characters", path.string()));
    return token;
}

}  // namespace

Daemon::Daemon(DaemonConfig config)
    : config_(std::move(config)), acceptor_(io_), signals_(io_, SIGINT, SIGTERM), drain_timer_(io_) {
    if (config_.token_file) token_ = read_token(*config_.token_file);
    if (!is_loopback(config_.listen_host) && !token_) {
        throw InputError(fmt::format("listening on {} (not loopback) needs --token-file", config_.listen_host));
    }
    if (config_.scene_root) {
        if (!std::filesystem::is_directory(*config_.scene_root)) {
            throw InputError(fmt::format("--scene-root {} is not a directory", config_.scene_root->string()));
        }
        scene_root_.root = std::filesystem::canonical(*config_.scene_root);
    }
    scene_root_.max_scene_bytes = config_.max_scene_bytes;
    scene_root_.max_scenes = config_.max_scenes;
    if (config_.priors_file) {
        try {
            priors_ = planning::OwnErrorPriors::read(*config_.priors_file);
        } catch (const InputError& error) {
            throw InputError(fmt::format("--priors: {}", error.what()));
        }
        log::info("daemon", "budgets plan with the own-error priors of {}", priors_.description());
    }
    render_ = std::make_unique<RenderService>(gpu::DeviceChoice::resolve(config_.device), config_.queue_capacity);
    // The built-in scene, and one tiny frame so every shader is compiled before we report ready.
    if (config_.cache_dir) {
        std::error_code error;
        std::filesystem::create_directories(*config_.cache_dir, error);
        if (error || !std::filesystem::is_directory(*config_.cache_dir)) {
            throw InputError(fmt::format("--cache-dir {} is not a directory that can be created ({})",
                                         config_.cache_dir->string(), error.message()));
        }
    }
    render_->run_and_wait([this](Renderer& renderer, SceneRegistry& registry) {
        renderer.set_cache_dir(config_.cache_dir);
        if (config_.gpu_memory_budget) renderer.set_memory_budget({*config_.gpu_memory_budget, "--gpu-memory-budget"});
        log::info("daemon", "GPU memory budget: {} ({})", bytes_text(renderer.memory_budget().bytes),
                  renderer.memory_budget().source);
        SceneEntry& entry = registry.put("cornell", scene::make_cornell_box(), "builtin");
        RenderRequest warmup;
        warmup.width = warmup.height = 8;
        renderer.render(*entry.resources, warmup);
    });
    log::info("daemon", "renderer ready: {}", render_->gpu_info().summary());
    metrics_.set_identity(render_->gpu_info().renderer, render_->gpu_info().software, config_.queue_capacity,
                          config_.max_clients);
}

Daemon::~Daemon() {
    render_.reset();  // jobs hold sessions, whose sockets need io_
    std::lock_guard lock(sessions_mutex_);
    sessions_.clear();
}

protocol::Limits Daemon::limits() const {
    protocol::Limits limits;
    const auto cap = static_cast<std::uint32_t>(std::min<std::size_t>(config_.max_message_bytes, UINT32_MAX));
    limits.max_json_bytes = std::min(limits.max_json_bytes, cap);
    limits.max_attachment_bytes = cap;
    return limits;
}

nlohmann::json Daemon::hello_body() const {
    const auto l = limits();
    return {{"server", "bounced/" BOUNCE_VERSION},
            {"protocol", protocol::kProtocolVersion},
            {"renderer", render_->gpu_info().renderer},
            {"limits", {{"max_json_bytes", l.max_json_bytes}, {"max_attachment_bytes", l.max_attachment_bytes},
                        {"max_in_flight", config_.max_in_flight}, {"max_pixels", config_.max_pixels}}},
            {"heartbeat_ms", config_.heartbeat.count()},
            {"methods", methods::MethodRegistry::builtin().names()}};
}

bool Daemon::try_start_cpu_job() {
    int jobs = cpu_jobs_.load();
    while (jobs < kMaxCpuJobs) {
        if (cpu_jobs_.compare_exchange_weak(jobs, jobs + 1)) return true;
    }
    return false;
}

void Daemon::request_started() { ++in_flight_; }
void Daemon::request_finished() { --in_flight_; }

void Daemon::forget(Session* session) {
    std::lock_guard lock(sessions_mutex_);
    for (auto it = sessions_.begin(); it != sessions_.end(); ++it) {
        if (it->get() == session) {
            sessions_.erase(it);
            break;
        }
    }
    std::erase_if(unauthenticated_, [&](const std::weak_ptr<Session>& weak) {
        const auto held = weak.lock();
        return !held || held.get() == session;
    });
    metrics_.set_connections(sessions_.size());
}

bool Daemon::authenticated(Session* session) {
    std::lock_guard lock(sessions_mutex_);
    std::erase_if(unauthenticated_, [&](const std::weak_ptr<Session>& weak) {
        const auto held = weak.lock();
        return !held || held.get() == session;
    });
    return sessions_.size() - unauthenticated_.size() <= config_.max_clients;
}

void Daemon::accept() {
    acceptor_.async_accept(asio::make_strand(io_), asio::bind_executor(accept_strand_, [this](boost::system::error_code error,
                                                                                              tcp::socket socket) {
        if (error) {
            if (error != asio::error::operation_aborted) log::warn("daemon", "accept failed: {}", error.message());
            if (acceptor_.is_open()) accept();
            return;
        }
        admit(make_tcp_transport(std::move(socket)));
        accept();
    }));
}

void Daemon::admit(std::unique_ptr<Transport> transport) {
    if (shutting_down_) {
        transport->close();
        return;
    }
    std::shared_ptr<Session> session;
    std::shared_ptr<Session> evicted;
    {
        std::lock_guard lock(sessions_mutex_);
        if (token_) {
            // Unauthenticated connections have their own cap; the oldest makes way, so a flood
            // of connections that never authenticate cannot keep a real client out.
            if (unauthenticated_.size() >= config_.max_unauthenticated) {
                evicted = unauthenticated_.front().lock();
                unauthenticated_.pop_front();
            }
            session = std::make_shared<Session>(*this, std::move(transport));
            unauthenticated_.push_back(session);
        } else if (sessions_.size() >= config_.max_clients) {
            log::warn("daemon", "refusing a {} client: {} connected (--max-clients)", transport->kind(), sessions_.size());
            transport->close();
        } else {
            session = std::make_shared<Session>(*this, std::move(transport));
        }
        if (session) {
            sessions_.insert(session);
            metrics_.set_connections(sessions_.size());
        }
    }
    if (evicted) {
        log::info("daemon", "closing the oldest unauthenticated connection (--max-unauthenticated {})",
                  config_.max_unauthenticated);
        evicted->close();
    }
    if (session) session->start();
}

void Daemon::start_http_server() {
    if (!config_.metrics_listen) return;
    http_ = std::make_unique<HttpServer>(*this, *config_.metrics_listen, config_.serve_viewer);
    http_->start();
}

void Daemon::begin_shutdown() {
    if (shutting_down_.exchange(true)) return;
    ready_ = false;
    streams_.stop_all();
    log::info("daemon", "shutting down: {} requests in flight", in_flight_.load());
    asio::dispatch(accept_strand_, [this] {
        boost::system::error_code ignored;
        acceptor_.close(ignored);
    });
    drain_deadline_ = std::chrono::steady_clock::now() + config_.drain_timeout;
    auto poll = std::make_shared<std::function<void()>>();
    *poll = [this, poll] {
        if (in_flight_.load() == 0 || std::chrono::steady_clock::now() > drain_deadline_) {
            if (in_flight_.load() != 0) log::warn("daemon", "drain deadline passed with {} in flight", in_flight_.load());
            std::vector<std::shared_ptr<Session>> open;
            {
                std::lock_guard lock(sessions_mutex_);
                open.assign(sessions_.begin(), sessions_.end());
            }
            for (auto& session : open) session->close();
            // Let the closes and last writes run, then stop.
            drain_timer_.expires_after(std::chrono::milliseconds(50));
            drain_timer_.async_wait([this](boost::system::error_code) { io_.stop(); });
            return;
        }
        drain_timer_.expires_after(std::chrono::milliseconds(20));
        drain_timer_.async_wait([poll](boost::system::error_code error) {
            if (!error) (*poll)();
        });
    };
    (*poll)();
}

void Daemon::stop() {
    asio::post(io_, [this] { begin_shutdown(); });
}

int Daemon::run() {
    const tcp::endpoint endpoint(asio::ip::make_address(config_.listen_host == "localhost" ? "127.0.0.1" : config_.listen_host),
                                 config_.listen_port);
    acceptor_.open(endpoint.protocol());
    acceptor_.set_option(tcp::acceptor::reuse_address(true));
    acceptor_.bind(endpoint);
    acceptor_.listen();
    const auto port = acceptor_.local_endpoint().port();
    start_http_server();
    if (config_.port_file) {
        // The protocol port, then the ops HTTP port when there is one (either may be asked as :0).
        const auto temporary = config_.port_file->string() + ".tmp";
        {
            std::ofstream out(temporary);
            out << port << "\n";
            if (http_) out << http_->port() << "\n";
        }
        std::filesystem::rename(temporary, *config_.port_file);
    }
    signals_.async_wait([this](boost::system::error_code error, int signal) {
        if (error) return;
        log::info("daemon", "signal {} received: draining for at most {} ms", signal, config_.drain_timeout.count());
        begin_shutdown();
        // A second signal means now: no drain, no cleanup.
        signals_.async_wait([](boost::system::error_code again, int second) {
            if (again) return;
            log::warn("daemon", "signal {} received again: exiting at once", second);
            std::_Exit(128 + second);
        });
    });
    accept();
    ready_ = true;
    log::info("daemon", "listening on {}:{} scene_root={} token={}", config_.listen_host, port,
              scene_root_.root ? scene_root_.root->string() : "none", token_ ? "required" : "not required");

    std::vector<std::thread> threads;
    for (int i = 1; i < config_.network_threads; ++i) threads.emplace_back([this] { io_.run(); });
    io_.run();
    for (auto& thread : threads) thread.join();
    cpu_pool_.join();         // CPU jobs may still hand frames to the render thread
    precompute_pool_.join();  // and finished bakes their frames (closed sessions cancelled the rest)
    render_->stop();
    encode_pool_.join();
    log::info("daemon", "stopped");
    return 0;
}

}  // namespace bounce::server
