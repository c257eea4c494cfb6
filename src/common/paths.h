#pragma once
/// @file Where the project's data (models/, scenarios/) lives at run time.

#include <string>

namespace hgrasp {

/// The project root: $HGRASP_ROOT if set, else the source tree the binary was built from.
std::string ProjectRoot();

/// `relative` resolved against ProjectRoot() unless it is absolute or exists as given.
std::string ResolveDataPath(const std::string& relative);

}  // namespace hgrasp
