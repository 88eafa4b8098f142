// Render statistics: cheap per-thread counters summed at the end.
//   GRADUS_STAT_COUNTER("Integrator/Camera rays", rays); ... ++rays;
#pragma once
#include <cstdint>
#include <map>
#include <mutex>
#include <string>
#include <vector>

namespace gradus {

class StatRegistry {
  public:
    static StatRegistry &get();
    // Registers a thread's counter cell (called once per thread per counter).
    void registerCell(const std::string &name, const uint64_t *cell);
    void unregisterCell(const uint64_t *cell, const std::string &name);
    // Sum over live threads plus retired threads.
    std::map<std::string, uint64_t> snapshot() const;
    void reset();

  private:
    mutable std::mutex mutex_;
    std::multimap<std::string, const uint64_t *> cells_;
    std::map<std::string, uint64_t> retired_;
};

class StatCounterCell {
  public:
    explicit StatCounterCell(const char *name) : name_(name) { StatRegistry::get().registerCell(name_, &value_); }
    ~StatCounterCell() { StatRegistry::get().unregisterCell(&value_, name_); }
    StatCounterCell &operator++() { ++value_; return *this; }
    StatCounterCell &operator+=(uint64_t v) { value_ += v; return *this; }

  private:
    std::string name_;
    uint64_t value_ = 0;
};

#define GRADUS_STAT_COUNTER(title, var) static thread_local ::gradus::StatCounterCell var(title)

// Formats a snapshot as "name: value" lines.
std::string FormatStats(const std::map<std::string, uint64_t> &s);

}  // namespace gradus
