#pragma once
//! Topology-aware wave simulation of §5, eq. (1): d2h/dt2 = c^2 laplace(h) on the tracked surface, h the
//! displacement along the normal. Per frame: the state (h, v) of frame n-1 is carried through frame n's
//! event list (§4.6; values keyed by persistent vertex ids), energy is injected only at vertices created by
//! topology changes (PatchCreate events), then the system is integrated over one frame time with
//! symplectic Euler sub-steps on frame n's mesh, optionally damped by h *= (1 - epsilon) per step.
#include <array>
#include <span>
#include <vector>

#include "io/event_list.hpp"
#include "kernels/wave/laplacian.hpp"

namespace topotrack {

struct WaveParams {
  double speed = 1.0;             //!< c, surface units per second (user-chosen in the paper)
  double frame_time = 1.0 / 30;   //!< seconds per input frame
  int substeps = 0;               //!< symplectic Euler steps per frame; <= 0: from the CFL bound
  double cfl_safety = 0.5;        //!< automatic sub-steps keep dt <= safety * 2 / (c sqrt(lambda_max))
  double damping = 0.0;           //!< epsilon; the paper used none
  double inject_height = 0.0;     //!< added to h at each vertex a topology patch creates (absolute units)
  double inject_velocity = 0.0;   //!< added to v there
};

//! h and v per vertex of the current frame, in the frame's vertex order, with the vertices' persistent ids.
struct WaveState {
  std::vector<VertexId> ids;
  std::vector<double> h, v;
};

struct WaveReport {
  int substeps = 0;
  double dt = 0;
  std::size_t injected = 0;        //!< vertices that received energy (transfer)
  std::size_t missing = 0;         //!< vertices of the new frame without a propagated value (set to 0)
  double energy_before = 0;        //!< after transfer, before integration
  double energy_after = 0;
  double max_abs_height = 0;
  double transfer_seconds = 0, laplacian_seconds = 0, integrate_seconds = 0;
};

//! A zero state for a frame's vertex ids.
WaveState zero_wave_state(std::span<const VertexId> ids);

//! Carry `state` (of frame n-1) through `events` (frame n-1 -> n) to the vertex ids `next_ids` of frame n
//! (§4.6 forward rules), adding inject_height / inject_velocity at each vertex created by a PatchCreate event
//! at the moment of creation (later re-sampling events then interpolate it like any value).
//! \throw InvalidInput when state's arrays disagree in size or ids repeat.
WaveState transfer_wave_state(const WaveState& state, const EventList& events, std::span<const VertexId> next_ids,
                              const WaveParams& params = {}, WaveReport* report = nullptr);

//! Wave energy 1/2 v^T M v + 1/2 c^2 h^T C h.
double wave_energy(const CotanLaplacian& L, const WaveState& state, double speed);

//! Sub-steps per frame that keep symplectic Euler stable on L.
int stable_substeps(const CotanLaplacian& L, const WaveParams& params);

//! Integrate over one frame time on the mesh (positions, triangles) whose vertex order matches `state`.
//! \throw InvalidInput on bad parameters or when state's size differs from the vertex count.
void integrate_waves(std::span<const Vec3> positions, std::span<const std::array<Index, 3>> triangles,
                     WaveState& state, const WaveParams& params = {}, WaveReport* report = nullptr);
//! The same on a prebuilt operator (for several frames on a fixed mesh).
void integrate_waves(const CotanLaplacian& L, WaveState& state, const WaveParams& params = {},
                     WaveReport* report = nullptr);

}  // namespace topotrack
