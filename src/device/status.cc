#include "device/status.h"

namespace hgrasp::device {

std::string_view ToString(Status s) {
  switch (s) {
    case Status::kOk:
      return "ok";
    case Status::kTimeout:
      return "timeout";
    case Status::kBadReply:
      return "bad reply";
    case Status::kRejected:
      return "rejected";
    case Status::kDisconnected:
      return "disconnected";
    case Status::kInterrupted:
      return "interrupted";
  }
  return "unknown";
}

}  // namespace hgrasp::device
