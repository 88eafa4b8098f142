// Errors: every user-facing failure is an exception whose message already
// carries its location ("file:line:column: what is wrong"); the tools print
// it on stderr and exit with status 1.
#pragma once
#include <memory>
#include <stdexcept>
#include <string>

namespace gradus {

struct FileLoc {
    std::shared_ptr<const std::string> file;  // shared by every token of one file
    int line = 1, column = 1;
    std::string filename() const { return file ? *file : std::string("<unknown>"); }
    std::string str() const {
        return filename() + ":" + std::to_string(line) + ":" + std::to_string(column);
    }
};

class Error : public std::runtime_error {
  public:
    explicit Error(const std::string &msg) : std::runtime_error(msg) {}
    // Located error: what() is "file:line:col: msg".
    Error(const FileLoc &loc, const std::string &msg)
        : std::runtime_error(loc.str() + ": " + msg), loc_(loc), located_(true) {}
    // The location of a located error (for callers that report it as data, e.g. the Python module).
    const FileLoc *location() const { return located_ ? &loc_ : nullptr; }

  private:
    FileLoc loc_;
    bool located_ = false;
};

// A known pbrt-v3 feature Gradus does not implement (still an error, exit 1).
class UnsupportedError : public Error {
  public:
    UnsupportedError(const FileLoc &loc, const std::string &what)
        : Error(loc, what + " is a pbrt-v3 feature that Gradus does not support yet") {}
};

[[noreturn]] void CheckFailed(const char *file, int line, const char *expr);
#define GRADUS_CHECK(x) ((x) ? (void)0 : ::gradus::CheckFailed(__FILE__, __LINE__, #x))
#ifdef NDEBUG
#define GRADUS_DCHECK(x) ((void)0)
#else
#define GRADUS_DCHECK(x) GRADUS_CHECK(x)
#endif

}  // namespace gradus
