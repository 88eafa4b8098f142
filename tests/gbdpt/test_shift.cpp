#include <gtest/gtest.h>
TEST(GBDPTShift, Placeholder) {}
