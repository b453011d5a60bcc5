// Runs a real bounced on an ephemeral loopback port for the duration of a test.
#pragma once

#include "client/client.hpp"

#include <chrono>
#include <filesystem>
#include <string>
#include <vector>

namespace bounce::test {

class DaemonProcess {
public:
    // Starts bounced with `extra` flags plus --listen 127.0.0.1:0 and a port file; waits until it
    // listens (or throws with its exit status). With `capture_log` its stderr goes to log_path().
    explicit DaemonProcess(std::vector<std::string> extra = {}, bool capture_log = false);
    ~DaemonProcess();  // SIGTERM, then SIGKILL after 20 s

    client::Endpoint endpoint() const { return {"127.0.0.1", port_}; }
    // The ops HTTP port, when started with --metrics-listen 127.0.0.1:0 (0 otherwise).
    std::uint16_t ops_port() const { return ops_port_; }
    // Sends SIGTERM and returns the exit status (the process's exit code, or 128 + signal).
    int terminate_and_wait();
    void send_signal(int signal) const;
    // Waits for the process to exit, at most `limit` (then SIGKILL, so the status says 128 + 9);
    // returns the exit status as terminate_and_wait does.
    int wait_for_exit(std::chrono::seconds limit);
    int pid() const { return pid_; }
    // The process's resident set size now, from /proc (kB).
    long resident_kb() const;
    // The most it has had resident since it started (VmHWM), in KiB.
    long peak_resident_kb() const;
    // CPU time it has used, user and system, in seconds.
    double cpu_seconds() const;
    // SIGKILL: the daemon gets no chance to clean up (a crash, or a machine going down).
    void kill_hard();
    bool running() const;
    const std::filesystem::path& directory() const { return directory_; }
    std::filesystem::path log_path() const { return directory_ / "log"; }

private:
    int pid_ = -1;
    std::uint16_t port_ = 0;
    std::uint16_t ops_port_ = 0;
    std::filesystem::path directory_;
};

}  // namespace bounce::test
