#include "app/runner.hpp"

#include "core/error.hpp"
#include "dynamics/system.hpp"
#include "io/checkpoint.hpp"
#include "io/field_vtk.hpp"
#include "io/files.hpp"
#include "io/monitors.hpp"
#include "io/progress.hpp"
#include "io/summary.hpp"
#include "io/vtk_writer.hpp"
#include "kiln/version.hpp"
#include "thermal/thermal_system.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <fmt/format.h>
#include <memory>

namespace kiln::app {

namespace {

/// Set by SIGINT/SIGTERM; the run loop stops cleanly at the next step.
volatile std::sig_atomic_t stop_requested = 0;

extern "C" void request_stop(int) {
    stop_requested = 1;
}

/// Installs the stop handlers for the lifetime of a run and restores the defaults afterwards.
struct StopHandlers {
    StopHandlers() {
        stop_requested = 0;
        std::signal(SIGINT, request_stop);
        std::signal(SIGTERM, request_stop);
    }
    ~StopHandlers() {
        std::signal(SIGINT, SIG_DFL);
        std::signal(SIGTERM, SIG_DFL);
    }
    StopHandlers(const StopHandlers&) = delete;
    StopHandlers& operator=(const StopHandlers&) = delete;
};

/// Steps between events of period `interval` (s); 0 when the event is off.
long every(double interval, double dt) {
    if (interval <= 0.0) {
        return 0;
    }
    return std::max(1L, std::lround(interval / dt));
}

/// The mechanical system of a case and, with [heat], its thermal system; their set-up errors
/// are prefixed by the case file.
std::pair<std::unique_ptr<dynamics::System>, std::unique_ptr<thermal::ThermalSystem>>
build_systems(const io::CaseSpec& spec) {
    std::unique_ptr<dynamics::System> sys;
    try {
        sys = std::make_unique<dynamics::System>(spec.scene);
    } catch (const InputError& e) {
        throw InputError(spec.source_file + ": " + e.what());
    }
    // Heat only when the case has a [heat] section: a scene without heat pays nothing.
    std::unique_ptr<thermal::ThermalSystem> heat;
    if (spec.heat.enabled) {
        try {
            heat = std::make_unique<thermal::ThermalSystem>(spec.heat, *sys);
        } catch (const InputError& e) {
            throw InputError(spec.source_file + ": " + e.what());
        }
    }
    return {std::move(sys), std::move(heat)};
}

} // namespace

void check_setup(const io::CaseSpec& spec) {
    (void)build_systems(spec);
}

int run_case(const io::CaseSpec& spec, const RunOptions& opt) {
    io::make_directory(opt.out_dir);
    io::write_text_file(
        opt.out_dir / "case.resolved.toml",
        fmt::format("# kiln {} (git {}), resolved from {}\n# every default filled in; "
                    "runs as it stands with `kiln run`\n\n{}",
                    kiln::version, kiln::git_hash, spec.source_file, spec.resolved_toml));

    auto systems = build_systems(spec);
    std::unique_ptr<dynamics::System>& sys = systems.first;
    std::unique_ptr<thermal::ThermalSystem>& heat = systems.second; // null without [heat]
    if (!opt.restart.empty()) {
        sys->restore_state(io::read_checkpoint(opt.restart));
        if (heat) {
            const auto saved = io::read_checkpoint_heat(opt.restart);
            if (!saved) {
                throw InputError(opt.restart.string(), 0, "",
                                 "the checkpoint has no temperatures but the case has [heat]");
            }
            heat->restore_state(*saved, *sys);
        }
    }
    const auto save_checkpoint = [&] {
        if (heat) {
            const thermal::ThermalState hs = heat->save_state();
            io::write_checkpoint(opt.out_dir / "checkpoint.bin", sys->save_state(), &hs);
        } else {
            io::write_checkpoint(opt.out_dir / "checkpoint.bin", sys->save_state());
        }
    };
    const auto& ts = sys->time_step_report();
    for (const auto& w : sys->warnings()) {
        fmt::print(stderr, "kiln: warning: {}\n", w);
    }
    const double dt = sys->dt();
    const long total = std::lround(spec.run.end_time / dt);
    const long vtk_every = every(spec.output.vtk_interval, dt);
    const long mon_every = every(spec.output.monitor_interval, dt);
    const long ckp_every = every(spec.output.checkpoint_interval, dt);
    constexpr long finite_check_every = 1000;

    if (!opt.quiet) {
        fmt::print("kiln {}: case '{}', {} particles, {} walls, {} steps of {:.3g} s\n",
                   kiln::version, spec.run.name, sys->particles().size(), spec.scene.walls.size(),
                   total - sys->step_count(), dt);
        fmt::print("  critical step: Rayleigh {:.3g} s, contact time {:.3g} s (dt = {:.2g} of the "
                   "smaller)\n",
                   ts.rayleigh, ts.contact_time, dt / ts.limit);
        if (heat) {
            fmt::print("  heat: thermal step {:.3g} s ({} mechanical steps), solver {} (tolerance "
                       "{:.2g})\n",
                       heat->time_step(), spec.heat.step_multiple,
                       heat::to_string(spec.heat.solver.kind), spec.heat.solver.tolerance);
            for (const auto& line : heat->describe()) {
                fmt::print("  heat: {}\n", line);
            }
        }
    }

    // A restart into the folder of the run it continues extends that run's series and monitor
    // rows from the checkpoint on; into a fresh folder it starts them at the checkpoint.
    const bool restarting = !opt.restart.empty();
    io::ParticleSeriesWriter vtk(opt.out_dir);
    vtk.set_heat(heat.get());
    const std::size_t frames_kept = restarting ? vtk.resume(sys->time()) : 0;
    std::unique_ptr<io::FieldSeriesWriter> fields;
    if (heat && spec.heat.field_output) {
        fields = std::make_unique<io::FieldSeriesWriter>(opt.out_dir, frames_kept);
    }
    // A particle frame, and with field output the intra-particle fields at the same time.
    const auto write_frame = [&] {
        vtk.write(*sys);
        if (fields) {
            fields->write(*sys, *heat, spec.heat.field_particles);
        }
    };
    if (!spec.scene.walls.empty() || !spec.scene.mesh_walls.empty()) {
        vtk.write_walls(spec.scene, opt.out_dir / "walls.vtp");
    }
    io::MonitorWriter monitors =
        restarting ? io::MonitorWriter(opt.out_dir / "monitors.csv", spec.output.monitors,
                                       io::ResumePoint{sys->time(), sys->step_count(), mon_every})
                   : io::MonitorWriter(opt.out_dir / "monitors.csv", spec.output.monitors);
    monitors.set_heat(heat.get());
    io::Progress progress(spec.run.end_time, spec.output.progress && !opt.quiet);

    io::RunSummary summary;
    summary.case_name = spec.run.name;
    summary.case_file = spec.source_file;
    summary.kiln_version = kiln::version;
    summary.git_hash = kiln::git_hash;
    summary.warnings = sys->warnings();
    summary.time_step = dt;
    summary.rayleigh_time_step = ts.rayleigh;
    summary.contact_time = ts.contact_time;
    summary.status = "completed";

    const long first = sys->step_count();
    if (vtk_every > 0 && frames_kept == 0) {
        write_frame();
    }
    if (monitors.rows() == 0) {
        monitors.write(*sys);
    }
    if (restarting && !opt.quiet) {
        fmt::print("  continuing from {} at t = {:.6g} s (step {}); kept {} frames and {} monitor "
                   "rows\n",
                   opt.restart.string(), sys->time(), sys->step_count(), frames_kept,
                   monitors.rows());
    }
    const auto t0 = std::chrono::steady_clock::now();
    double heat_wall = 0.0; // s spent in thermal steps (the clock is read only when heat is on)
    int code = 0;
    const StopHandlers handlers;
    bool interrupted = false;
    try {
        while (sys->step_count() < total) {
            if (stop_requested != 0) {
                interrupted = true;
                break;
            }
            // The steps up to the next one whose state is read (finite check, monitors, frames,
            // checkpoints; heat reads every step) in one call, so that the integrator can fuse its
            // passes over the particles between them. A stop request waits at most
            // finite_check_every steps.
            const long s0 = sys->step_count();
            long run =
                heat ? 1 : std::min(total, (s0 / finite_check_every + 1) * finite_check_every) - s0;
            for (const long every_n : {mon_every, vtk_every, ckp_every}) {
                if (every_n > 0) {
                    run = std::min(run, (s0 / every_n + 1) * every_n - s0);
                }
            }
            sys->advance(run);
            if (heat) {
                const auto h0 = std::chrono::steady_clock::now();
                heat->after_step(*sys);
                heat_wall +=
                    std::chrono::duration<double>(std::chrono::steady_clock::now() - h0).count();
            }
            const long s = sys->step_count();
            if (s % finite_check_every == 0) {
                sys->check_finite();
            }
            if (mon_every > 0 && s % mon_every == 0) {
                monitors.write(*sys);
            }
            if (vtk_every > 0 && s % vtk_every == 0) {
                write_frame();
            }
            if (ckp_every > 0 && s % ckp_every == 0) {
                save_checkpoint();
            }
            progress.update(sys->time(), s - first);
        }
        sys->check_finite();
    } catch (const RunError& e) {
        summary.status = std::string("failed: ") + e.what();
        code = 3;
        write_frame();
    }
    if (interrupted) {
        // Nothing is lost: the state at the last step goes to a checkpoint the run can resume from.
        summary.status = fmt::format("interrupted at t = {:.6g} s; resume with --restart {}",
                                     sys->time(), (opt.out_dir / "checkpoint.bin").string());
        code = 130;
        save_checkpoint();
        if (vtk_every > 0) {
            write_frame();
        }
    }
    progress.finish();
    const double wall =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

    summary.steps = sys->step_count() - first;
    summary.particles = static_cast<long>(sys->particles().size());
    summary.simulated_time = sys->time();
    summary.wall_seconds = wall;
    summary.heat_wall_seconds = heat_wall;
    summary.particle_steps_per_second =
        wall > 0.0
            ? static_cast<double>(summary.steps) * static_cast<double>(summary.particles) / wall
            : 0.0;
    summary.neighbour_builds = sys->neighbour_builds();
    summary.bodies = static_cast<long>(std::count_if(sys->particles().shape.begin(),
                                                     sys->particles().shape.end(),
                                                     [](std::int32_t k) { return k >= 0; }));
    summary.narrow_phase_calls = sys->narrow_phase_counters().calls;
    summary.narrow_phase_fallbacks = sys->narrow_phase_counters().fallbacks;
    summary.narrow_phase_failures = sys->narrow_phase_counters().failures;
    for (const auto& name : spec.output.monitors) {
        summary.final_monitors.emplace_back(name, io::monitor_value(*sys, heat.get(), name));
    }
    if (heat) {
        summary.sections.emplace_back("heat", heat->summary_json());
        for (const auto& w : heat->warnings()) {
            summary.warnings.push_back(w);
            fmt::print(stderr, "kiln: warning: {}\n", w);
        }
    }
    io::write_summary_json(opt.out_dir / "summary.json", summary);
    if (code == 0 && spec.output.checkpoint_interval > 0.0) {
        save_checkpoint();
    }

    if (!opt.quiet) {
        fmt::print("  {}: {} steps in {:.2f} s wall, {:.3g} particle-steps/s\n", summary.status,
                   summary.steps, wall, summary.particle_steps_per_second);
        for (const auto& [name, value] : summary.final_monitors) {
            fmt::print("  final {:<18} {:.6g}\n", name, value);
        }
        fmt::print("  output: {} (open particles.pvd in ParaView)\n", opt.out_dir.string());
    }
    if (code != 0) {
        fmt::print(stderr, "kiln: {}\n", summary.status);
    }
    return code;
}

} // namespace kiln::app
