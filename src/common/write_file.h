#pragma once
/// @file Files written whole or not at all: the bytes go to a temporary file beside the target,
/// which is renamed into place only once every byte is on disk.

#include <string>
#include <string_view>

namespace hgrasp {

/// Writes `bytes` to `path` through `path`.part, renamed into place when complete.
/// @throws std::runtime_error naming `path` and the system's reason when it cannot be opened,
///         written or moved into place (the temporary file is then removed).
void WriteFileWhole(const std::string& path, std::string_view bytes);

}  // namespace hgrasp
