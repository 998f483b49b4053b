#include <nlohmann/json.hpp>

#include "bindings.h"
#include "core/errors.h"
#include "core/version.h"

PYBIND11_MODULE(_core, m) {
  m.doc() = "iphong native core (use the `iphong` package)";
  // Bad input is ValueError, whatever layer found it (io names the file or field; the libraries
  // iphong parses with throw their own types); a wrong Python type is TypeError (arrays.h).
  // Messages are one line, as on the command line.
  pybind11::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const pybind11::builtin_exception&) {
      throw;  // TypeError and friends: pybind11's own translation
    } catch (const pybind11::error_already_set&) {
      throw;
    } catch (const iphong::OutputError& e) {
      PyErr_SetString(PyExc_OSError, iphong::OneLine(e.what()).c_str());
    } catch (const std::runtime_error& e) {  // ResourceError too: the request is the problem
      PyErr_SetString(PyExc_ValueError, iphong::OneLine(e.what()).c_str());
    } catch (const nlohmann::json::exception& e) {
      PyErr_SetString(PyExc_ValueError, iphong::OneLine(e.what()).c_str());
    }
  });
  m.attr("__version__") = iphong::kVersion;
  iphong::python::BindReflectance(m);
  iphong::python::BindRender(m);
  iphong::python::BindSolve(m);
  iphong::python::BindCalibrate(m);
  iphong::python::BindIntegrate(m);
  iphong::python::BindMaterial(m);
  iphong::python::BindIo(m);
  iphong::python::BindNear(m);
}
