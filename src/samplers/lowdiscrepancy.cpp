#include "samplers/lowdiscrepancy.h"

#include "core/error.h"

namespace gradus {

uint32_t Prime(int i) {
    GRADUS_CHECK(i >= 0 && i < PrimeTableSize);
    return kPrimeBases.base[i].b;
}

}  // namespace gradus
