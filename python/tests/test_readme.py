"""The README examples run as printed: every ```python block of python/README.md (in an empty
folder) and of the docs book's Python guide, docs/guides/python.md (on the shared data, skipped
when absent);
and, when mypy and scipy-stubs are installed (.ci/run installs them), each type-checks with
`mypy --strict` against the package's stubs."""

import contextlib
import io
import re
import subprocess
import sys
from importlib import metadata

import pytest

from conftest import REPO, skip


def python_blocks(text):
    """The ```python code blocks of a Markdown text."""
    return re.findall(r"```python\n(.*?)```", text, re.S)


PACKAGE_README = REPO / "python" / "README.md"
PYTHON_GUIDE = REPO / "docs" / "guides" / "python.md"
PACKAGE_BLOCKS = python_blocks(PACKAGE_README.read_text())


def from_python_section():
    """The code of the Python guide of the docs book (README.md links to it)."""
    return python_blocks(PYTHON_GUIDE.read_text())


def run(code, folder, monkeypatch):
    """Run `code` in `folder` as a script; its standard output."""
    monkeypatch.chdir(folder)
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        exec(compile(code, "<README>", "exec"), {"__name__": "__main__"})
    return out.getvalue()


def test_package_readme_has_examples():
    assert len(PACKAGE_BLOCKS) >= 5


@pytest.mark.parametrize("k", range(len(PACKAGE_BLOCKS)))
def test_package_readme_example_runs(k, tmp_path, monkeypatch):
    out = run(PACKAGE_BLOCKS[k], tmp_path, monkeypatch)
    assert "False" not in out, out  # the examples print True for their checks


def test_package_readme_outputs(tmp_path, monkeypatch):
    hand_eye = next(b for b in PACKAGE_BLOCKS if "rotavg.hand_eye(" in b)
    assert run(hand_eye, tmp_path, monkeypatch).split("\n")[:2] == ["True 28", "certified"]
    errors = next(b for b in PACKAGE_BLOCKS if "DisconnectedError" in b)
    assert run(errors, tmp_path, monkeypatch).split("\n")[:3] == ["[3, 2]", "[0 1 2] [2]", "bad.g2o 2"]
    files = next(b for b in PACKAGE_BLOCKS if "square.g2o" in b)
    assert run(files, tmp_path, monkeypatch).split("\n")[1] == "3 True"


def test_root_readme_example_runs(data_dir, tmp_path, monkeypatch):
    blocks = from_python_section()
    assert blocks, "docs/guides/python.md has no Python example"
    for code in blocks:
        code = code.replace("../shared/data", str(data_dir))
        out = run(code, tmp_path, monkeypatch)
        assert out.startswith("certified "), out


def test_examples_type_check(tmp_path):
    pytest.importorskip("mypy")
    try:
        metadata.version("scipy-stubs")
    except metadata.PackageNotFoundError:
        skip("scipy-stubs not installed: the examples are not type-checked")
    files = []
    for k, code in enumerate(PACKAGE_BLOCKS + from_python_section()):
        path = tmp_path / f"readme_example_{k}.py"
        path.write_text(code)
        files.append(str(path))
    out = subprocess.run(
        [sys.executable, "-m", "mypy", "--strict", "--no-incremental", *files],
        capture_output=True,
        text=True,
        cwd=tmp_path,
    )
    assert out.returncode == 0, out.stdout + out.stderr
