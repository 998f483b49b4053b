"""iphong used from outside its tree, as another project would: `cmake --install` into a prefix,
then a downstream CMake project (find_package) and a pkg-config build shade seed 002's example
through the public API; `pip install` into a fresh virtual environment, then estimate_normals on
DiLiGenT's ball crop. One version everywhere: CMake's project(VERSION)."""
import json
import os
import pathlib
import re
import shutil
import subprocess
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
BUILD = pathlib.Path(os.environ.get("IPHONG_BUILD_DIR", ROOT / "build"))
DATA = ROOT.parent / "shared" / "data"
VERSION = re.search(r"project\(iphong VERSION ([0-9.]+)", (ROOT / "CMakeLists.txt").read_text()).group(1)
SEED_002 = re.compile(r"I = \[0\.39273 0\.13292 0\.12634\]")

pytestmark = pytest.mark.skipif(not (BUILD / "CMakeCache.txt").is_file(),
                                reason=f"no configured build tree at {BUILD}")


def run(*args, **kwargs):
    result = subprocess.run([str(a) for a in args], capture_output=True, text=True, **kwargs)
    assert result.returncode == 0, f"{' '.join(map(str, args))}:\n{result.stdout}\n{result.stderr}"
    return result.stdout


@pytest.fixture(scope="module")
def prefix(tmp_path_factory):
    prefix = tmp_path_factory.mktemp("prefix")
    run("cmake", "--install", BUILD, "--prefix", prefix)
    return prefix


def test_the_install_holds_the_program_libraries_public_headers_and_packages(prefix):
    files = {p.relative_to(prefix).as_posix() for p in prefix.rglob("*") if p.is_file()}
    for name in ["bin/iphong", "include/iphong/reflectance/phong.h", "include/iphong/core/version.h",
                 "include/iphong/solve/normals.h", "include/iphong/near/near.h",
                 "include/iphong/io/dataset.h"]:
        assert name in files, name
    libdir = next(p.parent.relative_to(prefix).as_posix() for p in prefix.rglob("libiphong_core.a"))
    for role in ["core", "reflectance", "geometry", "render", "solve", "integrate", "calibrate",
                 "material", "near", "io"]:
        assert f"{libdir}/libiphong_{role}.a" in files, role
    for name in ["cmake/iphong/iphongConfig.cmake", "cmake/iphong/iphongConfigVersion.cmake",
                 "cmake/iphong/iphongTargets.cmake", "pkgconfig/iphong.pc"]:
        assert f"{libdir}/{name}" in files, name
    # Implementation headers stay out, but for the solver's inline helpers its headers use.
    internal = sorted(f for f in files if f.startswith("include/") and "internal" in f)
    assert internal == ["include/iphong/solve/internal.h"]
    assert not any(f.endswith(".cc") for f in files)
    assert run(prefix / "bin/iphong", "--version").strip() == f"iphong {VERSION}"
    package = [p for p in prefix.rglob("iphong/__init__.py")]
    assert len(package) == 1
    out = run(sys.executable, "-c", "import iphong; print(iphong.__version__, iphong.__file__)",
              cwd=prefix, env={**os.environ, "PYTHONPATH": str(package[0].parents[1])})
    assert out.split()[0] == VERSION and out.split()[1].startswith(str(prefix))


def test_a_downstream_cmake_project_builds_against_the_install(prefix, tmp_path):
    source = tmp_path / "downstream"
    shutil.copytree(ROOT / "tests/install/downstream", source)
    build = tmp_path / "build"
    run("cmake", "-S", source, "-B", build, f"-DCMAKE_PREFIX_PATH={prefix}")
    run("cmake", "--build", build)
    out = run(build / "seed002", tmp_path / "seed002.exr")
    assert SEED_002.search(out), out
    assert out.startswith(f"iphong {VERSION}:")
    assert "read back" in out  # io linked: OpenImageIO wrote and read the EXR
    # The package's version file refuses another minor version.
    (source / "CMakeLists.txt").write_text(
        (source / "CMakeLists.txt").read_text().replace("find_package(iphong 0.1", "find_package(iphong 9.0"))
    refused = subprocess.run(["cmake", "-S", source, "-B", tmp_path / "refused",
                              f"-DCMAKE_PREFIX_PATH={prefix}"], capture_output=True, text=True)
    assert refused.returncode != 0 and "iphong" in refused.stderr


def test_pkg_config_compiles_and_links_the_same_program(prefix, tmp_path):
    pc_dir = next(prefix.rglob("iphong.pc")).parent
    env = {**os.environ, "PKG_CONFIG_PATH": str(pc_dir)}
    assert run("pkg-config", "--modversion", "iphong", env=env).strip() == VERSION
    flags = run("pkg-config", "--cflags", "--libs", "iphong", env=env).split()
    program = tmp_path / "seed002"
    run("c++", ROOT / "tests/install/downstream/seed002.cc", "-o", program, *flags)
    out = run(program, tmp_path / "seed002.exr")
    assert SEED_002.search(out) and "read back" in out


@pytest.mark.skipif(not (DATA / "diligent-crop8" / "ball").is_dir(),
                    reason=f"DiLiGenT's ball crop not found under {DATA} (see ../shared/data/README.md)")
def test_pip_installs_into_a_virtual_environment(tmp_path):
    venv = tmp_path / "venv"
    run("/usr/bin/python3", "-m", "venv", "--system-site-packages", venv)
    python = venv / "bin" / "python"
    # The wheel's _core comes from this build tree (IPHONG_CMAKE_BUILD_DIR): the same CMake build
    # a fresh `pip install .` runs in build/pip/cmake, without compiling everything twice.
    run(python, "-m", "pip", "install", "--no-build-isolation", "--no-index", ROOT,
        env={**os.environ, "IPHONG_CMAKE_BUILD_DIR": str(BUILD)})
    script = (
        "import iphong\n"
        f"d = iphong.load_dataset({str(DATA / 'diligent-crop8' / 'ball')!r})\n"
        "r = iphong.estimate_normals(d['images'], d['light_directions'], d['light_intensities'], d['mask'])\n"
        "e = iphong.angular_error(r['normals'], d['normal_gt'], d['mask'])\n"
        "print(iphong.__version__, iphong.__file__, e['mean_angular_error_deg'])\n")
    out = run(python, "-c", script, cwd=tmp_path).split()
    assert out[0] == VERSION
    assert out[1].startswith(str(venv))  # the installed package, not the source tree's
    assert float(out[2]) <= 2.0  # 1.88 deg (README's accuracy table)
    run(python, "-m", "pip", "uninstall", "-y", "iphong")


def test_every_report_says_which_iphong_made_it(tmp_path):
    iphong = BUILD / "iphong"
    scene = ROOT / "fixtures" / "scenes" / "photometric_sphere.json"
    run(iphong, "render", scene, "-o", tmp_path / "capture", "--per-light")
    run(iphong, "normals", tmp_path / "capture", "-o", tmp_path / "normals", "--model", "lambert")
    run(iphong, "integrate", tmp_path / "normals", "-o", tmp_path / "height")
    for report in ["capture/render.json", "normals/metrics.json", "height/integrate.json"]:
        assert json.loads((tmp_path / report).read_text())["iphong_version"] == VERSION, report
    config_version = next((p for p in BUILD.glob("iphongConfigVersion.cmake")), None)
    assert config_version and f'set(PACKAGE_VERSION "{VERSION}")' in config_version.read_text()


def test_the_changelog_and_citation_name_this_version():
    changelog = (ROOT / "CHANGELOG.md").read_text()
    assert "## [Unreleased]" in changelog
    assert re.search(rf"^## \[{re.escape(VERSION)}\] - \d{{4}}-\d{{2}}-\d{{2}}$", changelog, re.M)
    citation = (ROOT / "CITATION.cff").read_text()
    assert re.search(rf"^version: {re.escape(VERSION)}$", citation, re.M)


def test_every_installed_header_compiles_on_its_own(prefix):
    """A user includes any one public header first: each must bring what it needs."""
    from concurrent.futures import ThreadPoolExecutor
    pc_dir = next(prefix.rglob("iphong.pc")).parent
    flags = run("pkg-config", "--cflags", "iphong",
                env={**os.environ, "PKG_CONFIG_PATH": str(pc_dir)}).split()
    include = prefix / "include" / "iphong"
    headers = sorted(h.relative_to(include).as_posix() for h in include.rglob("*.h"))
    assert len(headers) > 50

    def check(header):
        result = subprocess.run(["c++", *flags, "-fsyntax-only", "-x", "c++", "-"],
                                input=f'#include "{header}"\n', capture_output=True, text=True)
        return header, result.returncode, result.stderr[:500]

    with ThreadPoolExecutor(max_workers=os.cpu_count() or 2) as pool:
        failed = [(h, err) for h, code, err in pool.map(check, headers) if code != 0]
    assert not failed, failed
