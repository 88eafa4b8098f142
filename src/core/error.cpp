#include "core/error.h"

#include <cstdio>
#include <cstdlib>

namespace gradus {

void CheckFailed(const char *file, int line, const char *expr) {
    std::fprintf(stderr, "%s:%d: internal check failed: %s\n", file, line, expr);
    std::abort();
}

}  // namespace gradus
