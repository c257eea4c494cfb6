#include "serial/byte_link.h"

#include <string_view>

namespace hgrasp::drivers {

device::Status WriteText(ByteLink& link, std::string_view text) {
  return link.Write(std::span<const std::uint8_t>(
      reinterpret_cast<const std::uint8_t*>(text.data()), text.size()));
}

}  // namespace hgrasp::drivers
