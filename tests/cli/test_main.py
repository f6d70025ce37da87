"""No traceback reaches the user: bad input is one line and exit 2; anything else is one
line, exit 1 and a pointer to --debug; --debug shows the traceback."""

from __future__ import annotations

import pytest

from hairjax.cli import main


@pytest.fixture
def broken_render(monkeypatch):
    def boom(args):
        raise KeyError("an internal bug")

    monkeypatch.setattr("hairjax.cli._render.run", boom)


def test_an_unexpected_error_is_one_line(broken_render, capsys):
    assert main(["render"]) == 1
    err = capsys.readouterr().err
    assert err.strip().splitlines() == [
        "hairjax: unexpected error: KeyError: 'an internal bug' (rerun with --debug for the traceback)"
    ]


def test_debug_shows_the_traceback(broken_render):
    with pytest.raises(KeyError):
        main(["render", "--debug"])


@pytest.mark.parametrize(
    "argv, message",
    [
        (["render", "missing.toml"], "missing.toml"),
        (["render", "."], "."),
        (["info", "missing.hair"], "missing.hair"),
        (["view", "missing.exr"], "missing.exr"),
        (["fit", "--target", "missing.exr"], "missing.exr"),
        (["animate", "missing.toml"], "missing.toml"),
    ],
)
def test_missing_inputs_are_one_line(argv, message, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(argv) == 2
    err = capsys.readouterr().err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and message in lines[0] and "Traceback" not in err
    assert sorted(tmp_path.iterdir()) == []


def test_a_warning_is_one_line(monkeypatch, capsys):
    import warnings

    def warns(args):
        warnings.warn("the hair covers no pixel", UserWarning, stacklevel=1)
        return 0

    monkeypatch.setattr("hairjax.cli._render.run", warns)
    assert main(["render"]) == 0
    assert capsys.readouterr().err.strip().splitlines() == ["hairjax: warning: the hair covers no pixel"]


@pytest.mark.parametrize("placement", ["host", "device"])
def test_a_scene_beyond_memory_is_one_line_before_any_output(monkeypatch, tmp_path, capsys, placement):
    """Refused by the set-up's capacity policy (docs/model.md §5) where it runs: the host's
    memory for the compiled loops, the device's for the XLA programs."""
    from hairjax._geometry import _capacity, _device_raster
    from hairjax._geometry._placement import PLACEMENT_VARIABLE

    monkeypatch.setenv(PLACEMENT_VARIABLE, placement)  # the CLI's renders take the default
    monkeypatch.setattr(_capacity, "available_memory", lambda: 1000)  # bytes: nothing fits
    monkeypatch.setattr(_device_raster, "_free_bytes", lambda: 1000)
    out = tmp_path / "x.exr"
    assert main(["render", "--size", "64", "-o", str(out)]) == 2
    err = capsys.readouterr().err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in err
    # The first allocation bounded is the procedural hair's, before it is generated.
    assert lines[0].startswith("hairjax: error: hair.strands = 20,000 strands of hair.points = 16 points")
    assert lines[0].endswith("; 1000 bytes of memory is available")
    assert not out.exists()
