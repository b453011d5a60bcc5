#include "server/byte_budget.hpp"

namespace bounce::server {

bool ByteBudget::Reservation::grow(std::size_t bytes) {
    if (!budget_) return false;
    std::size_t used = budget_->used_.load();
    do {
        if (bytes > budget_->limit_ || used > budget_->limit_ - bytes) return false;
    } while (!budget_->used_.compare_exchange_weak(used, used + bytes));
    bytes_ += bytes;
    return true;
}

void ByteBudget::Reservation::release() {
    if (budget_ && bytes_ > 0) budget_->used_.fetch_sub(bytes_);
    bytes_ = 0;
}

}  // namespace bounce::server
