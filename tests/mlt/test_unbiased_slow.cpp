// Slow tier of the MLT agreement test (design in unbiased_util.h): 3x the
// runs and 2x the mutations of the default tier.
#include "unbiased_util.h"

namespace gradus::mlt_test {
namespace {

TEST(MLTUnbiasedSlow, BootstrapSizeSeedAndBdpt) { ExpectAgreement(600, 32); }

}  // namespace
}  // namespace gradus::mlt_test
