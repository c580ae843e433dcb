"""The written derivation of the derivatives of order k: its parts, its checks (each order the
derivative of the one below, symbolically for a small arm; the tensor against the numeric
reference), the program form of a long chain, the errors."""

from __future__ import annotations

import re

import pytest

from symkin.derive.higher_order import higher_order_derivation
from symkin.errors import ParameterError, SymkinError


def test_a_small_arm_is_written_out_and_checked_symbolically():
    text = higher_order_derivation("planar3", 3)
    headings = (
        "## What is differentiated",
        "## The rule: the product rule on cross products",
        "## The closed form",
        "## The Jacobian columns (order 1)",
        "## Order 2: 6 distinct columns",
        "## Order 3: 10 distinct columns",
        "## The tensor of order 3, block by block",
    )
    for heading in headings:
        assert heading in text
    assert text.count("$$\nD^{(3)}_{") == 9  # 3 x 3 blocks of 6 x 3, one display each
    derivative = "every block of orders 2..3 is the partial derivative of a block of the order below"
    assert f"{derivative}: the difference simplifies to 0" in text
    err = float(re.search(r"largest difference (\d\.\de[+-]\d+)", text).group(1))
    assert err < 1e-13


def test_a_prismatic_arm_checked_at_random_points():
    text = higher_order_derivation("stanford", 3)
    assert "vanishes at 3 random points to 30 digits" in text
    assert float(re.search(r"largest difference (\d\.\de[+-]\d+)", text).group(1)) < 1e-13


def test_a_long_chain_uses_the_program_form():
    text = higher_order_derivation("panda", 4, fmt="latex")
    assert text.startswith(r"\documentclass") and r"\zeta_{" in text
    assert "symkin derive panda --form program" in text
    assert "(Not listed: more than 40 multisets.)" in text  # 84 and 210 multisets
    assert float(re.search(r"largest difference (\d\.\de[+-]\d+)", text).group(1)) < 1e-13


def test_errors():
    with pytest.raises(SymkinError, match="--order 1 is the Jacobian"):
        higher_order_derivation("planar2", 1)
    with pytest.raises(ParameterError, match="order must be 1..8"):
        higher_order_derivation("planar2", 9)
    with pytest.raises(SymkinError, match="format"):
        higher_order_derivation("planar2", 3, fmt="html")
