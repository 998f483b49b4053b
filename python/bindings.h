// Shared declarations of the pybind11 bindings: one function per src/ role.
#pragma once

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

// estimate_normals' near lights (light_positions and the rest: the near-light loop) or, with
// directions only and 3 images or more, the effective distance (light_distance); fills `out`'s
// near-light entries and *result, or returns false to leave the solve to the caller.
bool SolveNear(const solve::PhotometricData& data, const solve::NormalOptions& options,
               const pybind11::object& light_positions, const pybind11::object& camera,
               const pybind11::object& light_axes, const pybind11::object& light_anisotropy,
               const pybind11::object& distance, const pybind11::object& light_distance,
               pybind11::dict& out, solve::NormalResult* result);

}  // namespace iphong::python
