"""Pages generated when the site is built, so they cannot drift from the code:

- reference/cli.md: `iphong --help` and every subcommand's --help, run on the built program;
- reference/cpp.md: every installed public header (src/ROLE/*.h but the internal ones) with the
  comment it opens with, role by role.

The Python reference (reference/python.md) is autodoc on the built module."""
import pathlib
import re
import subprocess

ROLES = ["core", "reflectance", "geometry", "render", "solve", "integrate", "calibrate",
         "material", "near", "io"]


def _help(program, *args):
    result = subprocess.run([str(program), *args, "--help"], capture_output=True, text=True,
                            timeout=60)
    if result.returncode != 0:
        raise RuntimeError(f"{program} {' '.join(args)} --help failed: {result.stderr}")
    return result.stdout.rstrip()


def cli_reference(program):
    top = _help(program)
    names = re.findall(r"^  ([a-z][a-z-]*)\s{2,}", top.split("Subcommands:")[1], re.M)
    text = ["# Command-line reference", "",
            "Generated from the program's own `--help` when this site was built.", "",
            "## iphong", "", "```text", top, "```", ""]
    for name in names:
        text += [f"## iphong {name}", "", "```text", _help(program, name), "```", ""]
    return "\n".join(text)


def _leading_comment(header):
    lines = []
    for line in header.read_text().splitlines():
        if line.startswith("//"):
            lines.append(line[2:].removeprefix(" "))
        elif lines or line.strip():
            break
    return "\n".join(lines)


def cpp_reference(src):
    text = ["# C++ reference", "",
            "The public headers, installed under `include/iphong` (`cmake --install`), role by "
            "role, each with the comment it opens with. Include them as `\"ROLE/NAME.h\"` with "
            "`include/iphong` on the include path (the CMake package and `iphong.pc` put it "
            "there).", ""]
    for role in ROLES:
        headers = sorted(p for p in (src / role).glob("*.h") if "internal" not in p.name)
        text += [f"## {role}", ""]
        for header in headers:
            text += [f"### `{role}/{header.name}`", ""]
            comment = _leading_comment(header)
            text += (["```text", comment, "```"] if comment else ["(no leading comment)"]) + [""]
    return "\n".join(text)


def _write_if_changed(path, text):
    path.parent.mkdir(parents=True, exist_ok=True)
    if not path.exists() or path.read_text() != text:
        path.write_text(text)


def generate(app):
    docs = pathlib.Path(app.srcdir)
    program = pathlib.Path(app.config.iphong_build_dir) / "iphong"
    if not program.is_file():
        raise RuntimeError(f"{program}: no iphong program; build it first (cmake --build build)")
    _write_if_changed(docs / "reference" / "cli.md", cli_reference(program))
    _write_if_changed(docs / "reference" / "cpp.md", cpp_reference(docs.parent / "src"))


def setup(app):
    app.add_config_value("iphong_build_dir", "", "env")
    app.connect("builder-inited", generate)
    return {"parallel_read_safe": True}
