"""robot.plot / symkin plot draw a PNG with matplotlib (the plot extra); a clear error without it."""

from __future__ import annotations

import builtins

import numpy as np
import pytest

import symkin
from symkin.errors import MissingExtraError
from symkin.model.plot import chain_points

PNG = b"\x89PNG\r\n\x1a\n"


def test_chain_points_follow_the_ets() -> None:
    r = symkin.load("puma560")
    q = r.random_q(seed=0)
    origins, joints, links = chain_points(r, q)
    assert len(origins) == len(r.ets) + 1 and len(joints) == len(links) == r.n
    np.testing.assert_allclose(origins[-1], r.fkine(q)[:3, 3], atol=1e-14)
    np.testing.assert_allclose(np.array(links), r.link_poses(q), atol=1e-14)


@pytest.mark.parametrize("name, ellipsoid", [("panda", True), ("cobra600", False), ("gantry", True)])
def test_plot_writes_a_png(tmp_path, name: str, ellipsoid: bool) -> None:
    pytest.importorskip("matplotlib")
    r = symkin.load(name)
    path = tmp_path / f"{name}.png"
    fig = r.plot(r.configs.get("qr", r.qz), ellipsoid=ellipsoid, path=path)
    assert path.read_bytes().startswith(PNG) and path.stat().st_size > 10_000
    ax = fig.axes[0]
    assert ax.get_xlabel() == "x (m)" and name in ax.get_title()
    if ellipsoid:
        assert "m per m/s" in ax.get_title()


def test_plot_without_matplotlib_says_what_to_install(monkeypatch) -> None:
    real = builtins.__import__

    def no_mpl(name, *args, **kwargs):  # noqa: ANN001, ANN002, ANN003, ANN202
        if name.startswith("matplotlib"):
            raise ImportError("No module named 'matplotlib'")
        return real(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", no_mpl)
    with pytest.raises(MissingExtraError, match=r"pip install 'symkin\[plot\]'"):
        symkin.load("ur5").plot()


def test_plot_checks_q() -> None:
    pytest.importorskip("matplotlib")
    r = symkin.load("ur5")
    with pytest.raises(symkin.ConfigurationError):
        r.plot([0.1, 0.2])
    with pytest.raises(ValueError, match="one configuration"):
        r.plot(r.random_q(2, seed=0))
