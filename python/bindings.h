// Shared declarations of the pybind11 bindings: one function per src/ role.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include "solve/normals.h"

namespace iphong::python {

void BindReflectance(pybind11::module_& m);
void BindRender(pybind11::module_& m);
void BindSolve(pybind11::module_& m);
void BindCalibrate(pybind11::module_& m);
void BindIntegrate(pybind11::module_& m);
void BindMaterial(pybind11::module_& m);
void BindIo(pybind11::module_& m);
void BindNear(pybind11::module_& m);

// estimate_normals' keyword arguments as the solver's options (the same for every entry point).
solve::NormalOptions OptionsFrom(const pybind11::object& model, const pybind11::object& material,
                                 double discard_dark, double discard_bright, bool fast,
                                 double shadow_threshold, int threads);
// light_intensities (K, 3), or None: all ones.
std::vector<Vec3d> Intensities(const pybind11::object& light_intensities, std::size_t k);
// A capture's size and K lights (checked as estimate_normals checks them), no pixel yet.
solve::PhotometricData NoObservations(int width, int height,
                                      const pybind11::object& light_directions,
                                      const pybind11::object& light_intensities, std::size_t k);
// A plan as plain Python values (plan_normals), and back.
pybind11::dict PlanDict(const solve::NormalPlan& plan);
solve::NormalPlan PlanFrom(const pybind11::object& value);
// A result's maps as one (h, w, 11) float32 array (solve_normals_block's layout), and back
// (`specular`, `model_map`: whether the result has those maps).
pybind11::array_t<float> MapsArray(const solve::NormalResult& r);
solve::NormalResult ResultFromMaps(const pybind11::object& maps, bool specular, bool model_map);

// estimate_normals' near lights (light_positions and the rest: the near-light loop) or, with
// directions only and 3 images or more, the effective distance (light_distance); fills `out`'s
// near-light entries and *result (with the effective distance, *distant the distant solve's),
// or returns false to leave the solve to the caller.
bool SolveNear(const solve::PhotometricData& data, const solve::NormalOptions& options,
               const pybind11::object& light_positions, const pybind11::object& camera,
               const pybind11::object& light_axes, const pybind11::object& light_anisotropy,
               const pybind11::object& distance, const pybind11::object& light_distance,
               pybind11::dict& out, solve::NormalResult* result,
               solve::NormalResult* distant = nullptr);

}  // namespace iphong::python
