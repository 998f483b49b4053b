// `iphong integrate NORMALS -o DIR`: heights and a mesh from a normal map.
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <sstream>

#include "integrate/integrate.h"
#include "io/dataset.h"
#include "io/image_io.h"
#include "io/staging.h"
#include "io/surface.h"
#include "io/visualize.h"
#include "iphong/commands.h"

namespace iphong::cli {
namespace {

namespace fs = std::filesystem;

struct IntegrateCommandOptions {
  std::string normals, mask, albedo, depth_prior, output_dir;
  std::string method = "auto", solver = "auto", convention = "opengl";
  std::vector<double> intrinsics;
  integrate::IntegrateOptions options;
  bool obj = false;
};

struct NormalInput {
  ImageF normals;
  Mask mask;
  ImageF albedo;
};

Mask MaskFromImage(const std::string& path) {
  const ImageF m = io::ReadImage(path);
  Mask mask(m.width, m.height, false);
  for (std::size_t p = 0; p < m.pixel_count(); ++p) mask.inside[p] = m.pixels[p * m.channels] > 0;
  return mask;
}

// A normal map file (EXR/TIFF floats, PNG pictures, Normal_gt.mat), the output directory of
// `iphong normals` (normals.exr, albedo.exr) or a dataset directory (its ground truth and mask).
NormalInput ReadNormalInput(const IntegrateCommandOptions& o) {
  NormalInput in;
  const fs::path path(o.normals);
  if (fs::is_directory(path)) {
    if (fs::exists(path / "normals.exr")) {
      in.normals = io::ReadImage((path / "normals.exr").string());
      if (fs::exists(path / "albedo.exr"))
        in.albedo = io::ReadImage((path / "albedo.exr").string());
    } else {
      io::DatasetLoadOptions load;
      load.load_images = false;
      io::Dataset d = io::LoadDataset(o.normals, load);
      if (d.normal_gt.pixels.empty()) {
        throw std::runtime_error(o.normals + ": neither normals.exr nor a ground-truth normal map");
      }
      in.normals = std::move(d.normal_gt);
      in.mask = std::move(d.mask);
    }
  } else if (path.extension() == ".mat") {
    in.normals = io::ReadNormalMat(o.normals, "Normal_gt");
  } else {
    ImageF image = io::ReadImage(o.normals);
    if (image.channels < 3) throw std::runtime_error(o.normals + ": a normal map needs 3 channels");
    const std::string ext = path.extension().string();
    if (ext == ".png" || ext == ".jpg" || ext == ".jpeg") {
      // Pictures store (n + 1)/2 (ReadImage undoes no transfer curve, as a normal picture has
      // none).
      in.normals = io::NormalsFromPicture(image, o.convention == "directx", &in.mask);
    } else {
      if (image.channels != 3) {
        ImageF rgb(image.width, image.height, 3);
        for (std::size_t p = 0; p < image.pixel_count(); ++p)
          for (int c = 0; c < 3; ++c) rgb.pixels[3 * p + c] = image.pixels[p * image.channels + c];
        image = std::move(rgb);
      }
      in.normals = std::move(image);
    }
  }
  if (!o.mask.empty()) {
    in.mask = MaskFromImage(o.mask);
  } else if (in.mask.width == 0) {
    in.mask = NonZeroPixels(in.normals);
  } else if (in.mask.width == in.normals.width && in.mask.height == in.normals.height) {
    in.mask = NonZeroPixels(in.normals, &in.mask);  // dataset masks include pixels GT leaves 0
  }
  if (!o.albedo.empty()) in.albedo = io::ReadImage(o.albedo);
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
  if (auto m = options.Validate(); !m.empty()) throw std::runtime_error(m);
  const NormalInput in = ReadNormalInput(o);
  if (!o.depth_prior.empty()) {
    options.depth_prior = io::ReadImage(o.depth_prior);
    if (options.depth_prior.channels != 1) {
      throw std::runtime_error(o.depth_prior + ": the depth prior must have one channel");
    }
  }
  const bool tty = ::isatty(2);
  if (tty) {
    options.progress = [](double fraction) {
      std::fprintf(stderr, "\rintegrating: %3.0f%%", 100 * fraction);
    };
  }
  integrate::IntegrateResult result;
  try {
    result = integrate::IntegrateNormals(in.normals, in.mask, options);
    if (tty) std::fprintf(stderr, "\r%20s\r", "");
  } catch (const std::invalid_argument& e) {
    const std::string source = o.mask.empty() ? o.normals : o.normals + " with mask " + o.mask;
    throw std::runtime_error(source + ": " + e.what());
  }
  io::StagingDirectory out(o.output_dir);
  io::SurfaceFileOptions files;
  files.obj = o.obj;
  files.albedo = in.albedo.pixels.empty() ? nullptr : &in.albedo;
  files.threads = options.threads;
  const io::SurfaceFiles written =
      io::WriteSurfaceFiles(out, result, in.normals, in.mask, io::FrameOf(options), files);
  out.Commit();

  const integrate::IntegrateSummary& s = result.summary;
  if (s.back_facing_pixels > 0) {
    std::fprintf(stderr,
                 "iphong: warning: %zu normals face away from the camera: taken as grazing\n",
                 s.back_facing_pixels);
  }
  std::printf("Integrated %zu pixels (%d part%s) with %s, %s: %.3f s (solve %.3f s%s)\n", s.pixels,
              s.components, s.components == 1 ? "" : "s", integrate::MethodName(s.method),
              s.solver.c_str(), s.total_seconds, s.solve_seconds,
              s.iterations ? (", " + std::to_string(s.iterations) + " CG iterations").c_str() : "");
  std::printf(
      "Surface normals vs input: mean %.2f deg, median %.2f deg; mesh %zu vertices, %zu "
      "triangles\n",
      written.consistency_mean_deg, written.consistency_median_deg, written.vertices,
      written.triangles);
  std::ostringstream names;
  for (std::size_t i = 0; i < written.names.size(); ++i)
    names << (i ? ", " : "") << written.names[i];
  std::printf("Wrote %s: %s\n", o.output_dir.c_str(), names.str().c_str());
}

}  // namespace

void AddIntegrateCommand(CLI::App& app) {
  auto o = std::make_shared<IntegrateCommandOptions>();
  auto* cmd = app.add_subcommand("integrate", "Heights and a mesh from a normal map");
  cmd->add_option("normals", o->normals,
                  "Normal map (EXR/TIFF xyz, PNG picture, Normal_gt.mat), an `iphong normals` "
                  "output directory, or a dataset directory (its ground truth)")
      ->required()
      ->check(CLI::ExistingPath);
  cmd->add_option("-o,--output", o->output_dir, "Output directory (replaced atomically)")
      ->required();
  cmd->add_option("--mask", o->mask, "Mask image (nonzero = object; default: pixels with a normal)")
      ->check(CLI::ExistingFile);
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
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--intrinsics", o->intrinsics,
                  "Perspective camera fx,fy,cx,cy in pixels: integrate log depth")
      ->delimiter(',')
      ->expected(4);
  cmd->add_option("--depth-prior", o->depth_prior,
                  "1-channel EXR of known heights (or depths with --intrinsics), NaN = unknown")
      ->check(CLI::ExistingFile);
  cmd->add_option("--prior-weight", o->options.prior_weight, "Weight of the depth prior per pixel")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--min-cos", o->options.min_cos,
                  "Grazing guard: smallest cosine between normal and view")
      ->check(CLI::Range(0.001, 0.9))
      ->capture_default_str();
  cmd->add_option("--stiffness", o->options.stiffness,
                  "bilateral: how sharply a depth step cuts (larger = more cuts)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--normal-map-convention", o->convention, "Green axis of PNG normal maps")
      ->check(CLI::IsMember({"opengl", "directx"}))
      ->capture_default_str();
  cmd->add_flag("--allow-back-facing", o->options.allow_back_facing,
                "Treat normals with nz <= 0 (silhouette pixels) as grazing instead of an error");
  cmd->add_flag("--obj", o->obj, "Also write mesh.obj");
  cmd->add_option("--threads", o->options.threads, "Threads (0 = all cores)")
      ->check(CLI::NonNegativeNumber);
  cmd->callback([o] { RunIntegrate(*o); });
}

}  // namespace iphong::cli
