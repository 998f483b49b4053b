// `iphong integrate NORMALS -o DIR`: heights and a mesh from a normal map.
#include <cstdio>
#include <filesystem>
#include <sstream>

#include "integrate/integrate.h"
#include "io/dataset.h"
#include "io/image_io.h"
#include "io/output_folder.h"
#include "io/surface.h"
#include "io/visualize.h"
#include "iphong/commands.h"
#include "iphong/console.h"

namespace iphong::cli {
namespace {

namespace fs = std::filesystem;

struct IntegrateCommandOptions {
  std::string normals, mask, albedo, depth_prior, output_dir;
  std::string method = "auto", solver = "auto", convention = "opengl";
  std::vector<double> intrinsics;
  integrate::IntegrateOptions options;
  bool obj = false;
  CommonOptions common;
};

struct NormalInput {
  ImageF normals;
  Mask mask;
  ImageF albedo;
};

// A normal map file (EXR/TIFF floats, PNG pictures, Normal_gt.mat), the output directory of
// `iphong normals` (normals.exr, albedo.exr) or a dataset directory (its ground truth and mask).
NormalInput ReadNormalInput(const IntegrateCommandOptions& o) {
  NormalInput in;
  const fs::path path(o.normals);
  const MemoryLimit memory = o.common.memory();
  std::error_code error;
  if (!fs::exists(path, error)) throw std::runtime_error(o.normals + ": no such file or folder");
  if (fs::is_directory(path)) {
    io::FinishInterruptedCommit(o.normals);  // never half of one run and half of another
    if (fs::exists(path / "normals.exr")) {
      in.normals = io::ReadImage((path / "normals.exr").string(), memory);
      if (fs::exists(path / "albedo.exr"))
        in.albedo = io::ReadImage((path / "albedo.exr").string(), memory);
    } else {
      io::DatasetLoadOptions load;
      load.load_images = false;
      load.memory = memory;
      io::Dataset d = io::LoadDataset(o.normals, load);
      if (d.normal_gt.pixels.empty()) {
        throw std::runtime_error(o.normals + ": neither normals.exr nor a ground-truth normal map");
      }
      in.normals = std::move(d.normal_gt);
      in.mask = std::move(d.mask);
    }
  } else {
    in.normals = io::ReadNormalMap(o.normals, o.convention == "directx", &in.mask, memory);
  }
  if (!o.mask.empty()) {
    in.mask = io::ReadMask(o.mask, memory);
  } else if (in.mask.width == 0) {
    in.mask = NonZeroPixels(in.normals);
  } else if (in.mask.width == in.normals.width && in.mask.height == in.normals.height) {
    in.mask = NonZeroPixels(in.normals, &in.mask);  // dataset masks include pixels GT leaves 0
  }
  if (in.mask.width == in.normals.width && in.mask.height == in.normals.height) {
    for (const std::string& w : io::CheckNormalMap(in.normals, &in.mask, o.normals)) Warn(w);
  }
  if (!o.albedo.empty()) {
    in.albedo = io::ReadImage(o.albedo, memory);
  }
  if (!in.albedo.pixels.empty() &&
      (in.albedo.width != in.normals.width || in.albedo.height != in.normals.height ||
       in.albedo.channels < 3)) {
    throw std::runtime_error((o.albedo.empty() ? o.normals + "/albedo.exr" : o.albedo) +
                             ": albedo must be an RGB image of the normal map's size");
  }
  return in;
}

void RunIntegrate(IntegrateCommandOptions& o) {
  integrate::IntegrateOptions& options = o.options;
  options.method = integrate::ParseMethod(o.method);
  options.solver = o.solver == "cholesky" ? integrate::LinearSolver::kCholesky
                   : o.solver == "cg"     ? integrate::LinearSolver::kConjugateGradient
                                          : integrate::LinearSolver::kAuto;
  if (!o.intrinsics.empty()) {
    if (o.intrinsics.size() != 4) throw std::runtime_error("--intrinsics takes fx,fy,cx,cy");
    options.perspective = true;
    options.intrinsics = {o.intrinsics[0], o.intrinsics[1], o.intrinsics[2], o.intrinsics[3]};
  }
  options.threads = o.common.threads;
  if (auto m = options.Validate(); !m.empty()) throw std::invalid_argument(m);
  // The output folder is checked before any work. It may be the `iphong normals` output it
  // reads: integrate adds its files there, keeping the others.
  io::OutputFolderOptions folder;
  folder.command = "integrate";
  folder.overwrite = o.common.overwrite;
  folder.inputs = {o.normals, o.mask, o.albedo, o.depth_prior};
  folder.joins = {"normals"};
  io::OutputFolder out(o.output_dir, folder);
  const NormalInput in = ReadNormalInput(o);
  if (!o.depth_prior.empty()) {
    options.depth_prior = io::ReadImage(o.depth_prior, o.common.memory());
    if (options.depth_prior.channels != 1) {
      throw std::runtime_error(o.depth_prior + ": the depth prior must have one channel");
    }
    if (options.depth_prior.width != in.normals.width ||
        options.depth_prior.height != in.normals.height) {
      throw std::runtime_error(o.depth_prior + ": is " +
                               SizeText(options.depth_prior.width, options.depth_prior.height) +
                               ", the normal map is " +
                               SizeText(in.normals.width, in.normals.height));
    }
  }
  auto progress = std::make_shared<Progress>("integrate", o.common.progress_mode());
  options.progress = [progress](double fraction) { progress->Update(fraction); };
  RequireMemory(
      o.common.memory(), io::EstimateSurfaceBytes(in.mask.count(), options),
      o.normals + ": integrating and meshing " + std::to_string(in.mask.count()) + " pixels");
  integrate::IntegrateResult result;
  try {
    result = integrate::IntegrateNormals(in.normals, in.mask, options);
    options.progress = nullptr;
    progress.reset();
  } catch (const std::invalid_argument& e) {
    // A value of the prior is the prior file's fault; the rest the normal map's (and mask's).
    const std::string what = e.what();
    const std::string source = what.rfind("the depth prior", 0) == 0 && !o.depth_prior.empty()
                                   ? o.depth_prior
                               : o.mask.empty() ? o.normals
                                                : o.normals + " with mask " + o.mask;
    throw std::runtime_error(source + ": " + what);
  }
  io::SurfaceFileOptions files;
  files.obj = o.obj;
  files.albedo = in.albedo.pixels.empty() ? nullptr : &in.albedo;
  files.threads = options.threads;
  const io::SurfaceFiles written =
      io::WriteSurfaceFiles(out, "", result, in.normals, in.mask, io::FrameOf(options), files);
  out.Commit();
  PrintJson(o.common, written.report);

  const integrate::IntegrateSummary& s = result.summary;
  if (s.back_facing_pixels > 0) {
    Warn(std::to_string(s.back_facing_pixels) +
         " normals face away from the camera: taken as grazing");
  }
  Say(o.common, "Integrated %zu pixels (%d part%s) with %s, %s: %.3f s (solve %.3f s%s)\n",
      s.pixels, s.components, s.components == 1 ? "" : "s", integrate::MethodName(s.method),
      s.solver.c_str(), s.total_seconds, s.solve_seconds,
      s.iterations ? (", " + std::to_string(s.iterations) + " CG iterations").c_str() : "");
  if (s.method == integrate::Method::kBilateral) {
    Say(o.common, "Bilateral cuts: %zu edges; %zu pixels cut away from the rest of their part\n",
        s.cut_edges, s.separated_pixels);
  }
  Say(o.common,
      "Surface normals vs input: mean %.2f deg, median %.2f deg; mesh %zu vertices, %zu "
      "triangles\n",
      written.consistency_mean_deg, written.consistency_median_deg, written.vertices,
      written.triangles);
  std::ostringstream names;
  for (std::size_t i = 0; i < written.names.size(); ++i)
    names << (i ? ", " : "") << written.names[i];
  Say(o.common, "Wrote %s: %s\n", o.output_dir.c_str(), names.str().c_str());
}

}  // namespace

void AddIntegrateCommand(CLI::App& app) {
  auto o = std::make_shared<IntegrateCommandOptions>();
  auto* cmd = app.add_subcommand("integrate", "Heights and a mesh from a normal map");
  cmd->add_option("normals", o->normals,
                  "Normal map (EXR/TIFF xyz, PNG picture, Normal_gt.mat), an `iphong normals` "
                  "output directory, or a dataset directory (its ground truth)")
      ->required();
  cmd->add_option("-o,--output", o->output_dir,
                  "Output folder: new or empty, an `iphong normals` output (the files are added "
                  "beside the normals), or an earlier integrate output with --overwrite")
      ->required();
  cmd->add_option("--mask", o->mask,
                  "Mask image (nonzero = object; default: pixels with a normal)");
  cmd->add_option("--method", o->method,
                  "auto (dct on a full rectangle, else quadratic), quadratic, dct, fft, bilateral "
                  "(keeps depth discontinuities)")
      ->check(CLI::IsMember({"auto", "quadratic", "dct", "fft", "bilateral"}))
      ->capture_default_str();
  cmd->add_option("--solver", o->solver, "Sparse solver: auto (multigrid CG), cg, cholesky")
      ->check(CLI::IsMember({"auto", "cg", "cholesky"}))
      ->capture_default_str();
  cmd->add_option("--albedo", o->albedo, "Albedo image: mesh colours and preview");
  cmd->add_option("--pixel-size", o->options.pixel_size, "Scene units per pixel (orthographic)")
      ->check(Scale())
      ->capture_default_str();
  cmd->add_option("--intrinsics", o->intrinsics,
                  "Perspective camera fx,fy,cx,cy in pixels: integrate log depth")
      ->delimiter(',')
      ->expected(4);
  cmd->add_option("--depth-prior", o->depth_prior,
                  "1-channel EXR of known heights (or depths with --intrinsics), NaN = unknown");
  cmd->add_option("--prior-weight", o->options.prior_weight, "Weight of the depth prior per pixel")
      ->check(Scale())
      ->capture_default_str();
  cmd->add_option("--min-cos", o->options.min_cos,
                  "Grazing guard: smallest cosine between normal and view")
      ->check(CLI::Range(0.001, 0.9))
      ->capture_default_str();
  cmd->add_option("--stiffness", o->options.stiffness,
                  "bilateral: how sharply a depth step cuts (larger = more cuts)")
      ->check(Positive())
      ->capture_default_str();
  cmd->add_option("--normal-map-convention", o->convention, "Green axis of PNG normal maps")
      ->check(CLI::IsMember({"opengl", "directx"}))
      ->capture_default_str();
  cmd->add_flag("--allow-back-facing", o->options.allow_back_facing,
                "Treat normals with nz <= 0 (silhouette pixels) as grazing instead of an error");
  cmd->add_flag("--obj", o->obj, "Also write mesh.obj");
  AddOverwriteOption(cmd, o->common);
  AddThreadsOption(cmd, o->common);
  AddMemoryOption(cmd, o->common);
  AddReportOptions(cmd, o->common);
  cmd->callback([o] { RunIntegrate(*o); });
}

}  // namespace iphong::cli
