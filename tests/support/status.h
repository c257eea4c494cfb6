#pragma once
/// @file Device statuses in tests. device::Status is [[nodiscard]]: a call a test needs to succeed
/// says so, and a failure names the call and the status.
///   EXPECT_OK(dev.laser->SetLaser(true));
///   ASSERT_OK(dev.cameras->Grab(&frame));

#include <gtest/gtest.h>

#include <ostream>

#include "device/status.h"

namespace hgrasp::device {

/// GoogleTest prints a Status by its name (found by argument-dependent lookup).
inline void PrintTo(Status s, std::ostream* os) { *os << ToString(s); }

}  // namespace hgrasp::device

#define EXPECT_OK(call) EXPECT_EQ((call), ::hgrasp::device::Status::kOk) << #call
#define ASSERT_OK(call) ASSERT_EQ((call), ::hgrasp::device::Status::kOk) << #call
