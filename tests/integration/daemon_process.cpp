#include "daemon_process.hpp"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <fstream>
#include <iterator>
#include <random>
#include <sstream>
#include <stdexcept>
#include <thread>

extern char** environ;

namespace bounce::test {

DaemonProcess::DaemonProcess(std::vector<std::string> extra, bool capture_log) {
    std::random_device random;
    directory_ = std::filesystem::temp_directory_path() / ("bounced-test-" + std::to_string(random()));
    std::filesystem::create_directories(directory_);
    const auto port_file = directory_ / "port";
    std::vector<std::string> args = {BOUNCED_PATH, "--listen", "127.0.0.1:0", "--port-file", port_file.string(),
                                     "--log-level", "warn"};
    args.insert(args.end(), extra.begin(), extra.end());
    std::vector<char*> argv;
    for (auto& arg : args) argv.push_back(arg.data());
    argv.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    const std::string log = log_path().string();
    if (capture_log) posix_spawn_file_actions_addopen(&actions, 2, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    const int spawned = posix_spawn(&pid_, BOUNCED_PATH, &actions, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    if (spawned != 0) throw std::runtime_error("cannot start " + std::string(BOUNCED_PATH));
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
    while (std::chrono::steady_clock::now() < deadline) {
        int status = 0;
        if (waitpid(pid_, &status, WNOHANG) == pid_) {
            pid_ = -1;
            throw std::runtime_error("bounced exited during startup with status " + std::to_string(status));
        }
        std::ifstream in(port_file);
        int port = 0;
        if (in >> port && port > 0) {
            port_ = static_cast<std::uint16_t>(port);
            int ops = 0;
            if (in >> ops && ops > 0) ops_port_ = static_cast<std::uint16_t>(ops);
            return;
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    throw std::runtime_error("bounced did not start listening within 120 s");
}

bool DaemonProcess::running() const {
    if (pid_ <= 0) return false;
    int status = 0;
    return waitpid(pid_, &status, WNOHANG) == 0;
}

int DaemonProcess::terminate_and_wait() {
    if (pid_ <= 0) return -1;
    send_signal(SIGTERM);
    return wait_for_exit(std::chrono::seconds(20));
}

void DaemonProcess::send_signal(int signal) const {
    if (pid_ > 0) kill(pid_, signal);
}

int DaemonProcess::wait_for_exit(std::chrono::seconds limit) {
    if (pid_ <= 0) return -1;
    int status = 0;
    const auto deadline = std::chrono::steady_clock::now() + limit;
    while (waitpid(pid_, &status, WNOHANG) == 0) {
        if (std::chrono::steady_clock::now() > deadline) {
            kill(pid_, SIGKILL);
            waitpid(pid_, &status, 0);
            break;
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    pid_ = -1;
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

namespace {
long status_kb(pid_t pid, const std::string& field) {
    std::ifstream status("/proc/" + std::to_string(pid) + "/status");
    std::string line;
    while (std::getline(status, line)) {
        if (line.rfind(field, 0) == 0) return std::stol(line.substr(field.size()));
    }
    return -1;
}
}  // namespace

long DaemonProcess::resident_kb() const { return status_kb(pid_, "VmRSS:"); }

long DaemonProcess::peak_resident_kb() const { return status_kb(pid_, "VmHWM:"); }

double DaemonProcess::cpu_seconds() const {
    std::ifstream stat("/proc/" + std::to_string(pid_) + "/stat");
    std::string text((std::istreambuf_iterator<char>(stat)), std::istreambuf_iterator<char>());
    // Fields after the command name (which may hold spaces) in parentheses: utime and stime are the
    // 14th and 15th fields of the line, the 12th and 13th after ") ".
    const auto close = text.rfind(')');
    if (close == std::string::npos) return -1.0;
    std::istringstream fields(text.substr(close + 2));
    std::string field;
    unsigned long long utime = 0, stime = 0;
    for (int i = 1; i <= 13 && fields >> field; ++i) {
        if (i == 12) utime = std::stoull(field);
        if (i == 13) stime = std::stoull(field);
    }
    return static_cast<double>(utime + stime) / static_cast<double>(sysconf(_SC_CLK_TCK));
}

void DaemonProcess::kill_hard() {
    if (pid_ <= 0) return;
    kill(pid_, SIGKILL);
    int status = 0;
    waitpid(pid_, &status, 0);
    pid_ = -1;
}

DaemonProcess::~DaemonProcess() {
    terminate_and_wait();
    std::error_code ignored;
    std::filesystem::remove_all(directory_, ignored);
}

}  // namespace bounce::test
