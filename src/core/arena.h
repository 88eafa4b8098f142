// Per-thread bump allocator for short-lived objects (BSDFs, BxDFs) of one
// sample; reset() after each sample. Objects must be trivially destructible
// or have their destructors not matter (no owned heap memory).
#pragma once
#include <cstddef>
#include <cstdlib>
#include <memory>
#include <new>
#include <utility>
#include <vector>

namespace gradus {

class Arena {
  public:
    explicit Arena(size_t blockSize = 64 * 1024) : blockSize_(blockSize) {}
    Arena(const Arena &) = delete;
    Arena &operator=(const Arena &) = delete;

    void *alloc(size_t bytes, size_t align = alignof(std::max_align_t)) {
        size_t off = (used_ + align - 1) & ~(align - 1);
        if (blocks_.empty() || off + bytes > blockCap_) {
            nextBlock(bytes + align);
            off = (used_ + align - 1) & ~(align - 1);
        }
        used_ = off + bytes;
        return current_ + off;
    }
    template <typename T, typename... Args>
    T *make(Args &&...args) {
        return new (alloc(sizeof(T), alignof(T))) T(std::forward<Args>(args)...);
    }
    // Frees everything allocated since construction (keeps the memory).
    void reset() {
        cur_ = 0;
        used_ = 0;
        if (!blocks_.empty()) { current_ = blocks_[0].ptr.get(); blockCap_ = blocks_[0].size; }
    }

  private:
    struct Block { std::unique_ptr<char[]> ptr; size_t size; };
    void nextBlock(size_t minBytes) {
        if (!blocks_.empty() && cur_ + 1 < blocks_.size() && blocks_[cur_ + 1].size >= minBytes) {
            ++cur_;
        } else {
            size_t sz = std::max(blockSize_, minBytes);
            blocks_.insert(blocks_.begin() + (blocks_.empty() ? 0 : cur_ + 1), Block{std::make_unique<char[]>(sz), sz});
            cur_ = blocks_.size() == 1 ? 0 : cur_ + 1;
        }
        current_ = blocks_[cur_].ptr.get();
        blockCap_ = blocks_[cur_].size;
        used_ = 0;
    }
    size_t blockSize_;
    std::vector<Block> blocks_;
    size_t cur_ = 0, used_ = 0, blockCap_ = 0;
    char *current_ = nullptr;
};

}  // namespace gradus
