// Raw byte (de)serialisation of trivially copyable values for integrator
// checkpoint states (Integrator::saveState / loadState).
#pragma once
#include <cstring>
#include <string>
#include <type_traits>

namespace gradus {

template <typename T>
void PutBytes(std::string *s, const T &v) {
    static_assert(std::is_trivially_copyable_v<T>);
    s->append(reinterpret_cast<const char *>(&v), sizeof v);
}

// Reads a T at *at and advances it; false when the bytes run out.
template <typename T>
bool GetBytes(const std::string &s, size_t *at, T *v) {
    static_assert(std::is_trivially_copyable_v<T>);
    if (s.size() - *at < sizeof(T)) return false;
    std::memcpy(v, s.data() + *at, sizeof(T));
    *at += sizeof(T);
    return true;
}

}  // namespace gradus
