// Primary sample space (Kelemen, Szirmay-Kalos, Antal, Csonka 2002): the state
// of a Markov chain is the infinite vector of uniform numbers that drives the
// path sampler. Kept lazily, as in pbrt-v3 (book Sec. 16.4.4): a coordinate is
// materialised when the path sampler first reads it, and the mutations it has
// missed since are applied when it is read again.
//
// Mutations (Kelemen et al. 2002; the kernels of pbrt-v3, Sec. 16.4.4):
//   large step (probability largestepprobability): every coordinate replaced by
//     a fresh uniform number (an independent proposal);
//   small step: every coordinate moved by a normal offset of deviation sigma,
//     wrapped into [0, 1).
// Both are symmetric, T(x -> y) = T(y -> x), so the acceptance is min(1, I(y) / I(x)).
//
// Lazy bookkeeping. time_ counts accepted mutations (the state's age); a
// proposal is built at time time_ + 1. A coordinate holds its value as of its
// `time`; every accepted mutation since then was a small step unless one was a
// large step after it (time < lastLarge_: the value was replaced by an unseen
// uniform number, drawn now). n accepted small steps and the proposal's own
// compose to one normal offset of deviation sigma sqrt(n + 1) (on the real
// line; wrapping commutes with the sum). A coordinate read for the first time
// gets a fresh uniform value for the current state: unread coordinates are
// uniform and independent of everything read so far, whatever the chain did.
//
// Streams (Hachisuka et al. 2014, Sec. 4; pbrt-v3's three): coordinate k of
// stream s is element k * kStreams + s, so the camera subpath, the light
// subpath and the connection each read their own numbers whatever the
// length of the others.
#pragma once
#include <cmath>
#include <cstdint>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "samplers/rng.h"
#include "samplers/sampler.h"

namespace gradus::mlt {

enum Stream { kCameraStream = 0, kLightStream = 1, kConnectionStream = 2, kStreams = 3 };

class PrimarySampler : public Sampler {
  public:
    PrimarySampler(Float sigma, Float largeStepProbability)
        : Sampler(1, 0), sigma_(sigma), pLarge_(largeStepProbability) {}

    // A new state (bootstrap sample, chain start): every coordinate is drawn
    // from `rng` when first read, in reading order.
    void restart(RNG *rng) {
        coords_.clear();
        rng_ = rng;
        time_ = lastLarge_ = 0;
        proposing_ = large_ = false;
    }
    // Source of the fresh numbers of later reads and mutations.
    void setRNG(RNG *rng) { rng_ = rng; }
    // Starts a proposal: a large step with probability largestepprobability.
    void propose() {
        proposing_ = true;
        large_ = rng_->uniform() < pLarge_;
    }
    bool largeStep() const { return large_; }
    // The proposal becomes the state.
    void accept() {
        ++time_;
        if (large_) lastLarge_ = time_;
        proposing_ = false;
    }
    // The state stays: coordinates read by the proposal get their values back.
    void reject() {
        for (Coord &c : coords_)
            if (c.time == time_ + 1) {
                c.value = c.backup;
                c.time = c.backupTime;
            }
        proposing_ = false;
    }
    // Subsequent get1D/get2D read stream `s` from its coordinate `at` (0: the first).
    void startStream(int s, int64_t at = 0) {
        stream_ = s;
        next_ = at;
    }
    // The coordinate of the current stream that the next get1D reads.
    int64_t streamPosition() const { return next_; }
    int64_t coordinates() const { return int64_t(coords_.size()); }
    // Checkpoints: the state between mutations (coordinates with their ages,
    // the age and the last large step), appended to / read from bytes.
    void save(std::string *out) const {
        auto put = [out](const void *p, size_t n) { out->append(static_cast<const char *>(p), n); };
        const uint64_t n = coords_.size();
        put(&n, 8);
        put(coords_.data(), n * sizeof(Coord));
        put(&time_, 8);
        put(&lastLarge_, 8);
    }
    // Reads what save() wrote at *at; false when the bytes run out.
    bool load(const std::string &in, size_t *at) {
        auto get = [&](void *p, size_t n) {
            if (in.size() - *at < n) return false;
            std::memcpy(p, in.data() + *at, n);
            *at += n;
            return true;
        };
        uint64_t n;
        if (!get(&n, 8) || n > (in.size() - *at) / sizeof(Coord)) return false;
        coords_.resize(n);
        proposing_ = large_ = false;
        return get(coords_.data(), n * sizeof(Coord)) && get(&time_, 8) && get(&lastLarge_, 8);
    }

    // Sampler interface (the path sampler's view): reads the current stream.
    void startPixelSample(Point2i, int64_t, int dimension) override {
        stream_ = kCameraStream;
        next_ = dimension;
    }
    Float get1D() override { return read(size_t(next_++) * kStreams + size_t(stream_)); }
    Point2 get2D() override {
        Float x = get1D();
        Float y = get1D();
        return Point2(x, y);
    }
    std::unique_ptr<Sampler> clone() const override { return std::make_unique<PrimarySampler>(*this); }
    std::string name() const override { return "mlt primary sample space"; }

  private:
    static constexpr int64_t kUnread = -1;
    struct Coord {
        double value = 0;
        int64_t time = kUnread;  // state age the value belongs to
        double backup = 0;       // value and time before the current proposal
        int64_t backupTime = kUnread;
    };

    static double Wrap(double v) {
        v -= std::floor(v);
        return v < 1 ? v : OneMinusEpsilon;  // -tiny - floor(-tiny) rounds to 1
    }
    // Standard normal deviate (Box-Muller, cosine branch).
    double normal() {
        double u1 = 1 - rng_->uniform(), u2 = rng_->uniform();
        return std::sqrt(-2 * std::log(u1)) * std::cos(2 * Pi * u2);
    }

    double read(size_t i) {
        if (i >= coords_.size()) coords_.resize(i + 1);
        Coord &c = coords_[i];
        if (c.time == kUnread) {
            c.value = rng_->uniform();
            c.time = time_;
        } else if (c.time < lastLarge_) {
            c.value = rng_->uniform();
            c.time = lastLarge_;
        }
        const int64_t proposal = time_ + 1;
        if (!proposing_ || c.time == proposal) return c.value;
        c.backup = c.value;
        c.backupTime = c.time;
        if (large_)
            c.value = rng_->uniform();
        else
            c.value = Wrap(c.value + sigma_ * std::sqrt(double(proposal - c.time)) * normal());
        c.time = proposal;
        return c.value;
    }

    Float sigma_, pLarge_;
    RNG *rng_ = nullptr;
    std::vector<Coord> coords_;
    int64_t time_ = 0, lastLarge_ = 0;
    bool proposing_ = false, large_ = false;
    int stream_ = kCameraStream;
    int64_t next_ = 0;
};

}  // namespace gradus::mlt
