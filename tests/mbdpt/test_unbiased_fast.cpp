// Default tier of the M-BDPT / BDPT agreement tests (see unbiased_util.h).
#include "unbiased_util.h"

namespace gradus::mbdpt_test {
namespace {

TEST(MBDPTUnbiased, DistanceReorder) {
    ExpectAgreement("\"string reorder\" \"distance\" \"integer connections\" 1", 100);
    ExpectAgreement("\"string reorder\" \"distance\" \"integer connections\" 2", 200);
    ExpectAgreement("\"string reorder\" \"distance\" \"integer connections\" 4", 300);
}

}  // namespace
}  // namespace gradus::mbdpt_test
