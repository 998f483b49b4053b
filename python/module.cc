#include "bindings.h"
#include "core/version.h"

PYBIND11_MODULE(_core, m) {
  m.doc() = "iphong native core (use the `iphong` package)";
  m.attr("__version__") = iphong::kVersion;
  iphong::python::BindReflectance(m);
  iphong::python::BindRender(m);
  iphong::python::BindSolve(m);
  iphong::python::BindIntegrate(m);
}
