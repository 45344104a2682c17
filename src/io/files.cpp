#include "io/files.hpp"

#include "core/error.hpp"

#include <fstream>
#include <system_error>

namespace kiln::io {

void make_directory(const std::filesystem::path& dir) {
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (ec) {
        throw InputError(dir.string(), 0, "", "cannot create the output folder: " + ec.message());
    }
}

void write_text_file(const std::filesystem::path& file, const std::string& text) {
    std::ofstream f(file, std::ios::trunc);
    f << text;
    if (!f) {
        throw InputError(file.string(), 0, "", "cannot write the file");
    }
}

} // namespace kiln::io
