#include "samplers/lowdiscrepancy.h"

#include <vector>

#include "core/error.h"

namespace gradus {

namespace {
std::vector<uint32_t> MakePrimes() {
    std::vector<uint32_t> primes;
    for (uint32_t n = 2; int(primes.size()) < PrimeTableSize; ++n) {
        bool prime = true;
        for (uint32_t p : primes) {
            if (p * p > n) break;
            if (n % p == 0) { prime = false; break; }
        }
        if (prime) primes.push_back(n);
    }
    return primes;
}
}  // namespace

uint32_t Prime(int i) {
    static const std::vector<uint32_t> primes = MakePrimes();
    GRADUS_CHECK(i >= 0 && i < PrimeTableSize);
    return primes[i];
}

}  // namespace gradus
