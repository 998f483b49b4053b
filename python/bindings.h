// Shared declarations of the pybind11 bindings: one function per src/ role.
#pragma once

#include <pybind11/pybind11.h>

namespace iphong::python {

void BindReflectance(pybind11::module_& m);
void BindRender(pybind11::module_& m);
void BindSolve(pybind11::module_& m);
void BindCalibrate(pybind11::module_& m);
void BindIntegrate(pybind11::module_& m);
void BindMaterial(pybind11::module_& m);
void BindIo(pybind11::module_& m);

}  // namespace iphong::python
