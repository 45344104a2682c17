#pragma once
// VTK XML output that ParaView opens: a particle series (.vtp frames listed in a .pvd collection)
// and the analytic walls as polydata. The only file in kiln that includes VTK headers.

#include "dynamics/scene_spec.hpp"
#include "dynamics/system.hpp"
#include "geometry/surface_mesh.hpp"
#include "thermal/thermal_system.hpp"

#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace kiln::io {

/// Writes particle frames out_dir/particles/particles_NNNNNN.vtp and keeps out_dir/particles.pvd
/// listing every frame written so far, so the series can be opened at any moment during a run.
/// Scenes with non-spherical particles also get out_dir/bodies/bodies_NNNNNN.vtp (+ bodies.pvd):
/// every body's posed surface mesh (m, world frame) with per-cell particle id and velocity.
class ParticleSeriesWriter {
  public:
    /// Creates out_dir/particles/; throws InputError when it cannot.
    explicit ParticleSeriesWriter(std::filesystem::path out_dir);

    /// Continues the series in this folder after a restart at simulated time `time` (s): keeps the
    /// frames of particles.pvd up to `time`, deletes the files of later frames (written by the
    /// interrupted run after its checkpoint) and numbers new frames after the kept ones. Returns
    /// the number of frames kept (0 when there is no series yet). Throws InputError when an
    /// existing particles.pvd cannot be read.
    std::size_t resume(double time);

    /// Writes the particles of `sys` as the next frame (positions in m, world frame; SI fields)
    /// and rewrites particles.pvd atomically. Throws InputError when a file cannot be written.
    void write(const dynamics::System& sys);

    /// Writes the walls of `scene` to `file` (.vtp): planes as rectangles covering the particle
    /// region enlarged by 20 %, cylinders as open 48-sided tubes over that region, mesh walls as
    /// their triangles (m, world frame). Cell data "wall" is the wall index (mesh walls after the
    /// analytic ones); field data "wall_name" lists the names in that order. Throws InputError when
    /// the file cannot be written.
    void write_walls(const dynamics::SceneSpec& scene, const std::filesystem::path& file) const;

    /// Temperatures written with every frame from now on (point data temperature_mean,
    /// temperature_core, temperature_surface in K; NaN for particles without a heat model).
    /// `heat` may be null; it must outlive the writer's use.
    void set_heat(const thermal::ThermalSystem* heat) { heat_ = heat; }

    /// Number of particle frames written so far.
    [[nodiscard]] std::size_t frames() const { return frames_.size(); }

  private:
    /// One written frame: simulated time (s) and file path relative to the output folder.
    struct Frame {
        double time;
        std::string file;
    };

    void write_collection(const std::vector<Frame>& frames, const std::string& pvd) const;
    std::size_t resume_collection(double time, const std::string& pvd, std::vector<Frame>& frames);
    void write_bodies(const dynamics::System& sys);

    std::filesystem::path dir_;
    std::vector<Frame> frames_;
    const thermal::ThermalSystem* heat_ = nullptr;
    std::vector<Frame> body_frames_;
    std::map<int, geometry::SurfaceMesh> meshes_; // body-frame mesh per shape template
};

} // namespace kiln::io
