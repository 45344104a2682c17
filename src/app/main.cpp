// The `kiln` command line.

#include "app/runner.hpp"
#include "app/shape_info.hpp"
#include "core/error.hpp"
#include "io/case_reader.hpp"
#include "kiln/version.hpp"

#include <CLI/CLI.hpp>
#include <fmt/format.h>

int main(int argc, char** argv) {
    CLI::App cli{"kiln: discrete element method with non-spherical particles and heat"};
    cli.set_version_flag("--version",
                         std::string("kiln ") + kiln::version + " (git " + kiln::git_hash + ")");
    cli.require_subcommand(1);

    std::string case_file;
    kiln::app::RunOptions opt;
    std::string out_dir;
    std::string restart;
    auto* run = cli.add_subcommand("run", "run a case file");
    run->add_option("case", case_file, "case file (TOML), see docs/case-format.md")->required();
    run->add_option("--out", out_dir, "output folder (default: out/<case name>)");
    run->add_option("--restart", restart, "continue from this checkpoint file");
    run->add_flag("--quiet", opt.quiet, "no progress line and no summary on stdout");

    auto* check =
        cli.add_subcommand("check", "validate a case file and print it with defaults filled in");
    check->add_option("case", case_file, "case file (TOML)")->required();

    std::string shape_name;
    double density = 1000.0;
    auto* info = cli.add_subcommand("info", "print volume, mass properties and shape factors of a "
                                            "shape template (shapes/README.md)");
    info->add_option("shape", shape_name, "template name (shapes/NAME.toml) or path to a .toml")
        ->required();
    std::string vtk_file;
    info->add_option("--vtk", vtk_file,
                     "also write the template's surface mesh (.vtp) for ParaView");
    info->add_option("--density", density, "material density (kg/m^3)")
        ->capture_default_str()
        ->check(CLI::PositiveNumber);

    CLI11_PARSE(cli, argc, argv);
    try {
        if (info->parsed()) {
            return kiln::app::print_shape_info(shape_name, density, vtk_file);
        }
        const kiln::io::CaseSpec spec = kiln::io::read_case_file(case_file);
        if (check->parsed()) {
            kiln::app::check_setup(spec); // the start-up refusals of `kiln run` too
            fmt::print("{}", spec.resolved_toml);
            return 0;
        }
        opt.out_dir = out_dir.empty() ? std::filesystem::path("out") / spec.run.name
                                      : std::filesystem::path(out_dir);
        opt.restart = restart;
        return kiln::app::run_case(spec, opt);
    } catch (const kiln::InputError& e) {
        fmt::print(stderr, "kiln: error: {}\n", e.what());
        return 2;
    }
}
