// A daemon-wide budget for bytes held on behalf of clients (request bodies as they arrive, and the
// attachments of requests still running). Memory follows arrival: a body grows chunk by chunk as
// its bytes come in, each chunk reserved here first, so a header that announces a large body costs
// nothing until the bytes exist, and many slow uploads together cannot exceed the budget.
#pragma once

#include <atomic>
#include <cstddef>

namespace bounce::server {

class ByteBudget {
public:
    explicit ByteBudget(std::size_t limit) : limit_(limit) {}
    std::size_t limit() const { return limit_; }
    std::size_t used() const { return used_.load(); }

    // Bytes reserved from a budget, given back when the reservation goes.
    class Reservation {
    public:
        Reservation() = default;
        explicit Reservation(ByteBudget& budget) : budget_(&budget) {}
        Reservation(Reservation&& other) noexcept : budget_(other.budget_), bytes_(other.bytes_) { other.bytes_ = 0; }
        Reservation& operator=(Reservation&& other) noexcept {
            if (this != &other) {
                release();
                budget_ = other.budget_;
                bytes_ = other.bytes_;
                other.bytes_ = 0;
            }
            return *this;
        }
        Reservation(const Reservation&) = delete;
        Reservation& operator=(const Reservation&) = delete;
        ~Reservation() { release(); }

        // Reserves `bytes` more; false (and nothing reserved) when the budget cannot hold them.
        bool grow(std::size_t bytes);
        std::size_t bytes() const { return bytes_; }
        void release();

    private:
        ByteBudget* budget_ = nullptr;
        std::size_t bytes_ = 0;
    };

private:
    std::size_t limit_;
    std::atomic<std::size_t> used_{0};
};

}  // namespace bounce::server
