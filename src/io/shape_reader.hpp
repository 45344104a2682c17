#pragma once
// Shape template files (TOML) in shapes/: format in shapes/README.md. Mass properties are computed
// by kiln::geometry from the geometry in the file; the file never states mass or inertia.

#include "geometry/shape.hpp"

#include <filesystem>
#include <string>
#include <vector>

namespace kiln::io {

/// Reads one shape template file; the template name is the file stem. Throws kiln::InputError
/// with file:line: key on any problem (unknown key, wrong type, value out of range).
[[nodiscard]] geometry::ShapeTemplate read_shape_file(const std::filesystem::path& file);

/// Parses shape template text (`name` is used for messages and as the template name).
[[nodiscard]] geometry::ShapeTemplate read_shape_text(const std::string& text,
                                                      const std::string& name);

/// Folders searched for NAME.toml, in order: $KILN_SHAPES (if set), ./shapes, the source tree's
/// shapes/ folder.
[[nodiscard]] std::vector<std::filesystem::path> default_shape_dirs();

/// Resolves a shape given by name (NAME.toml in `dirs`) or by a path to a .toml file; throws
/// kiln::InputError listing the folders searched when nothing is found.
[[nodiscard]] std::filesystem::path find_shape_file(const std::string& name_or_path,
                                                    const std::vector<std::filesystem::path>& dirs);

/// Loads every *.toml of a folder into a registry.
[[nodiscard]] geometry::ShapeRegistry load_shape_folder(const std::filesystem::path& dir);

} // namespace kiln::io
