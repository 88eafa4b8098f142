#include "core/stats.h"

#include <sstream>

namespace gradus {

StatRegistry &StatRegistry::get() {
    static StatRegistry *r = new StatRegistry;  // never destroyed: thread exits may run late
    return *r;
}

void StatRegistry::registerCell(const std::string &name, const uint64_t *cell) {
    std::lock_guard<std::mutex> l(mutex_);
    cells_.emplace(name, cell);
}

void StatRegistry::unregisterCell(const uint64_t *cell, const std::string &name) {
    std::lock_guard<std::mutex> l(mutex_);
    auto range = cells_.equal_range(name);
    for (auto it = range.first; it != range.second; ++it)
        if (it->second == cell) {
            retired_[name] += *cell;
            cells_.erase(it);
            return;
        }
}

std::map<std::string, uint64_t> StatRegistry::snapshot() const {
    std::lock_guard<std::mutex> l(mutex_);
    std::map<std::string, uint64_t> out = retired_;
    for (const auto &c : cells_) out[c.first] += *c.second;
    return out;
}

void StatRegistry::reset() {
    std::lock_guard<std::mutex> l(mutex_);
    retired_.clear();
    for (auto &c : cells_) *const_cast<uint64_t *>(c.second) = 0;
}

std::string FormatStats(const std::map<std::string, uint64_t> &s) {
    std::ostringstream os;
    for (const auto &kv : s) os << "  " << kv.first << ": " << kv.second << "\n";
    return os.str();
}

}  // namespace gradus
