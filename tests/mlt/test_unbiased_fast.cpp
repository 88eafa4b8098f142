// Default tier of the MLT agreement test (design in unbiased_util.h).
#include "unbiased_util.h"

namespace gradus::mlt_test {
namespace {

TEST(MLTUnbiased, BootstrapSizeSeedAndBdpt) { ExpectAgreement(200, 16); }

}  // namespace
}  // namespace gradus::mlt_test
