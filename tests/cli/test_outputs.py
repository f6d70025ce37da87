"""Every output a command writes is checked before the work: the bad-output matrix.

For each subcommand that writes, and each way an output can be unwritable — its parent
is a file, its folder is read-only, its extension is not one the command writes, it is a
directory (for a folder output: it is a file) — the command exits 2 with one line that
names the path, shows no traceback, writes nothing, and fails before the work: the
function that would load the scene (or the image, or start the benchmark) is replaced by
one that fails the test if called.
"""

from __future__ import annotations

import contextlib
import os
import re
import subprocess
from pathlib import Path

import numpy as np
import pytest

import hairjax as hj
from hairjax._io._image import ImageError
from hairjax.cli import main
from hairjax.cli._outputs import (
    FILE_OVERHEAD,
    BadOutput,
    Output,
    check_output,
    check_outputs,
    image_bytes,
    written_together,
)


@contextlib.contextmanager
def read_only_folder(tmp_path: Path):
    """A folder nothing may be written into: chmod 555 for a user; for root (whom
    permissions do not stop) a read-only bind mount, or skip when mounting is refused."""
    folder = tmp_path / "ro"
    folder.mkdir()
    if os.geteuid() != 0:
        folder.chmod(0o555)
        try:
            yield folder
        finally:
            folder.chmod(0o755)
        return
    mounted = subprocess.run(["mount", "--bind", "-o", "ro", str(folder), str(folder)], capture_output=True)
    if mounted.returncode != 0:
        pytest.skip("root, and a read-only bind mount is refused here")
    try:
        assert not os.access(folder, os.W_OK)  # the mount is read-only, or the case proves nothing
        yield folder
    finally:
        subprocess.run(["umount", str(folder)], check=True)


# command → (argv before the output, the option naming the output, the output's kind, the
# function that starts the work). "file" outputs have extensions; "folder" outputs are filled.
EXR = "t.exr"
COMMANDS = {
    "render -o": (["render"], "-o", ".exr", "hairjax.cli._scenes.load_cli_scene"),
    "render --png": (["render"], "--png", ".png", "hairjax.cli._scenes.load_cli_scene"),
    "reference -o": (["reference"], "-o", ".exr", "hairjax.cli._scenes.load_cli_scene"),
    "view -o": (["view", EXR], "-o", ".png", "hairjax._io._image.read_image"),
    "compare --json": (["compare"], "--json", ".json", "hairjax.cli._scenes.load_cli_scene"),
    "fit --json": (["fit", "--target", EXR], "--json", ".json", "hairjax._io._image.read_image"),
    "fit --out": (["fit", "--target", EXR], "--out", ".exr", "hairjax._io._image.read_image"),
    "fit --plot": (["fit", "--target", EXR], "--plot", ".png", "hairjax._io._image.read_image"),
    "bench --json": (["bench", "--quick"], "--json", ".json", "hairjax.tools.bench_main"),
    "animate -o": (["animate", "scene.toml"], "-o", "folder", "hairjax._animate.load_animation"),
    "sweep --out": (["sweep"], "--out", "folder", "hairjax.cli._scenes.load_cli_scene"),
    "sweep --joint --out": (["sweep", "--joint"], "--out", "folder", "hairjax.cli._scenes.load_cli_scene"),
}
CASES = ("parent is a file", "read-only folder", "unsupported extension", "directory as output")


@pytest.mark.parametrize("case", CASES)
@pytest.mark.parametrize("command", COMMANDS)
def test_bad_output_fails_before_the_work(command, case, tmp_path, monkeypatch, capsys):
    before, option, kind, work = COMMANDS[command]
    if kind == "folder" and case == "unsupported extension":
        pytest.skip("a folder output has no extension to refuse (any name is a valid folder)")
    monkeypatch.chdir(tmp_path)
    hj.write_image(tmp_path / EXR, np.zeros((4, 4, 4)))
    (tmp_path / "scene.toml").write_text('[hair]\nsource = "furball"\n')
    module, name = work.rsplit(".", 1)

    def never(*args, **kwargs):
        raise AssertionError(f"{work} ran before the output was checked")

    monkeypatch.setattr(f"{module}.{name}", never)
    suffix = ".exr" if kind == "folder" else kind
    with contextlib.ExitStack() as stack:
        if case == "parent is a file":
            (tmp_path / "afile").write_text("x")
            target = tmp_path / "afile" / f"out{suffix}"
        elif case == "read-only folder":
            target = stack.enter_context(read_only_folder(tmp_path)) / f"out{suffix}"
        elif case == "unsupported extension":
            target = tmp_path / "out.jpg"
        else:
            target = tmp_path / "adir"
            if kind == "folder":
                target.write_text("a file where a folder should be")
            else:
                target.mkdir()
        listing = sorted(p.relative_to(tmp_path) for p in tmp_path.rglob("*"))
        code = main([*before, option, str(target)])
        err = capsys.readouterr().err
        assert code == 2
        lines = err.strip().splitlines()
        assert len(lines) == 1 and "Traceback" not in err, err
        assert str(target) in lines[0]
        assert sorted(p.relative_to(tmp_path) for p in tmp_path.rglob("*")) == listing  # nothing written


@pytest.mark.skipif(not os.path.isdir("/proc/self"), reason="needs Linux's /proc")
def test_a_folder_that_refuses_files_is_refused_before_the_work(tmp_path):
    """/proc passes `os.access(W_OK)` for root, but no file can be created there: the probe
    finds that before the work, and names the path (it used to fail after a whole fit, naming
    a temporary file)."""
    with pytest.raises(BadOutput, match=r"^/proc/x\.json \(--json\): /proc is not writable"):
        check_output(Output(Path("/proc/x.json"), (".json",), "--json"))
    check_output(Output(tmp_path / "x.json", (".json",), "--json"))
    assert list(tmp_path.iterdir()) == []  # the probe leaves nothing


def test_check_output_accepts_a_new_nested_path(tmp_path):
    check_output(Output(tmp_path / "a" / "b" / "c.exr", (".exr",), "-o"))  # created at write time
    check_output(Output(tmp_path / "new" / "folder", (), "--out"))
    assert list(tmp_path.iterdir()) == []  # checking creates nothing


def test_extension_check_ignores_case(tmp_path):
    check_output(Output(tmp_path / "A.EXR", (".exr",), "-o"))


def test_the_same_path_twice_is_refused(tmp_path):
    with pytest.raises(BadOutput, match="named by both -o and --png"):
        check_outputs(
            [Output(tmp_path / "a.png", (".png",), "-o"), Output(tmp_path / "a.png", (".png",), "--png")]
        )


def test_written_together_is_all_or_nothing(tmp_path):
    a, b = tmp_path / "a.txt", tmp_path / "sub" / "b.txt"
    with pytest.raises(RuntimeError):
        with written_together([a, b]) as (ta, tb):
            ta.write_text("a")
            tb.write_text("b")
            raise RuntimeError("the second writer failed")
    assert not a.exists() and not b.exists()
    assert [p.name for p in tmp_path.rglob("*") if p.is_file()] == []  # no temporary left
    with written_together([a, b]) as (ta, tb):
        ta.write_text("a")
        tb.write_text("b")
    assert a.read_text() == "a" and b.read_text() == "b"


def test_render_without_output_and_only_png_writes_only_the_png(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    scene = tmp_path / "s.toml"
    scene.write_text(
        '[hair]\nsource = "furball"\nstrands = 30\npoints = 4\n[camera]\nwidth = 16\nheight = 12\n'
    )
    assert main(["render", str(scene), "--png", "v.png", "-q"]) == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.toml", "v.json", "v.png"]


TINY = '[hair]\nsource = "furball"\nstrands = 30\npoints = 4\n[camera]\nwidth = 16\nheight = 12\n'


def test_png_takes_only_a_png(tmp_path, capsys):
    (tmp_path / "s.toml").write_text(TINY)
    assert main(["render", str(tmp_path / "s.toml"), "--png", str(tmp_path / "x.exr")]) == 2
    err = capsys.readouterr().err
    assert f"{tmp_path / 'x.exr'} (--png): unsupported extension '.exr'; use .png" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.toml"]


def test_the_same_path_for_o_and_png_names_both_options(tmp_path, capsys):
    a = tmp_path / "a.png"
    assert main(["render", "-o", str(a), "--png", str(a)]) == 2
    assert f"{a}: named by both -o and --png" in capsys.readouterr().err


def test_the_image_is_renamed_last_and_a_failed_rename_restores_the_old_files(tmp_path, monkeypatch):
    """The sidecar and the image of a render before it; a rename that fails (here the
    image's, the last) leaves both old files, and no temporary."""
    image, sidecar = tmp_path / "r.exr", tmp_path / "r.json"
    image.write_text("old image")
    sidecar.write_text("old sidecar")
    renamed = []
    real_replace = os.replace

    def replace(src, dst):
        if Path(dst) == image and not Path(src).name.endswith(".old"):
            raise PermissionError(13, "Permission denied")
        renamed.append(Path(dst).name)
        return real_replace(src, dst)

    monkeypatch.setattr(os, "replace", replace)
    with pytest.raises(OSError) as raised:
        with written_together([image, sidecar]) as (ti, ts):
            ti.write_text("new image")
            ts.write_text("new sidecar")
    assert raised.value.filename == str(image) and raised.value.strerror == "Permission denied"
    assert image.read_text() == "old image" and sidecar.read_text() == "old sidecar"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["r.exr", "r.json"]  # no temporary left
    monkeypatch.setattr(os, "replace", real_replace)
    renamed.clear()
    monkeypatch.setattr(os, "replace", lambda s, d: renamed.append(Path(d).name) or real_replace(s, d))
    with written_together([image, sidecar]) as (ti, ts):
        ti.write_text("new image")
        ts.write_text("new sidecar")
    assert [n for n in renamed if not n.endswith(".old")] == ["r.json", "r.exr"]  # the image last
    assert image.read_text() == "new image" and sidecar.read_text() == "new sidecar"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["r.exr", "r.json"]


def test_a_failed_write_names_the_users_path_not_the_temporary(tmp_path):
    image = tmp_path / "r.exr"
    with pytest.raises(OSError) as raised:
        with written_together([image]) as (tmp,):
            raise OSError(28, "No space left on device", str(tmp))
    assert str(raised.value) == f"[Errno 28] No space left on device: '{image}'"
    with pytest.raises(OSError, match=rf"^{re.escape(str(image))}: write failed: disk full$"):
        with written_together([image]) as (tmp,):
            raise ImageError(f"{tmp}: write failed: disk full")
    assert list(tmp_path.iterdir()) == []


def test_a_full_disk_is_refused_before_the_work(tmp_path, monkeypatch, capsys):
    """statvfs says 1000 bytes are free: the 16 × 12 EXR and its sidecar need more. The
    refusal comes after the scene is read (its size gives the image's) and before the render."""
    (tmp_path / "s.toml").write_text(TINY)

    class Full:
        f_bavail, f_frsize = 1, 1000

    monkeypatch.setattr(os, "statvfs", lambda path: Full())

    def never(*args, **kwargs):
        raise AssertionError("rendered on a full disk")

    monkeypatch.setattr("hairjax._render.render_profiled", never)
    out = tmp_path / "r.exr"
    assert main(["render", str(tmp_path / "s.toml"), "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1, err
    assert f"{out} (-o), {tmp_path / 'r.json'} (the sidecar" in err
    assert f"but {tmp_path} has 1000 bytes free" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.toml"]


def test_image_bytes_bounds_the_written_file(tmp_path):
    """The estimate is an upper bound of what write_image writes (noise: deflate gains nothing)."""
    image = np.random.default_rng(0).random((40, 50, 4))
    for name in ("a.exr", "a.png"):
        hj.write_image(tmp_path / name, image)
        size = (tmp_path / name).stat().st_size
        assert size <= image_bytes(tmp_path / name, 50, 40) < size + 2 * FILE_OVERHEAD
