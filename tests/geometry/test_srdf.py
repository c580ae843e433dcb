"""SRDFs written by symkin (symkin.geometry.srdf): the pairs it disables, checked against the NumPy
reference on random configurations; the file parsed back by a plain XML parser (the elements and
attributes srdfdom reads) and by symkin's reader; URDF link names; the conservative reading."""

from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np
import pytest

import symkin
from symkin.errors import GeometryError
from symkin.geometry import Geometry, Sphere, distances, layout_of
from symkin.geometry.srdf import disabled_pairs, read_srdf, srdf_disabled, write_srdf
from symkin.geometry.urdf import geometry_from_urdf, urdf_carriers


@pytest.fixture(scope="module")
def panda():
    return symkin.load("panda")


def test_never_pairs_stay_apart_and_adjacent_pairs_are_never_checked(panda):
    pairs = disabled_pairs(panda)
    reasons = {(a, b): r for a, b, r in pairs}
    assert set(reasons.values()) == {"Adjacent", "Never"}
    # the model's own disabled pairs are judged afresh, not copied: the UR5's covering model
    # disables (link3, link5) (their spheres overlap at a named configuration), so no proof holds
    ur5 = symkin.load("ur5")
    assert ("link3", "link5") in ur5.geometry.disabled
    assert ("link3", "link5") not in {(a, b) for a, b, _ in disabled_pairs(ur5)}
    layout = layout_of(panda.with_geometry(Geometry(panda.geometry.shapes)))
    shapes = layout.shapes
    checked = {tuple(sorted((shapes[i].link, shapes[j].link))) for i, j in layout.self_pairs}
    links = sorted(panda.geometry.links)
    # Adjacent: exactly the link pairs the layout never checks (one body, or one joint apart)
    adjacent = {(a, b) for k, a in enumerate(links) for b in links[k + 1 :]} - checked
    assert {p for p, r in reasons.items() if r == "Adjacent"} == adjacent
    # Never: every shape pair between the two links keeps apart on 20 000 random configurations
    Q = panda.random_q(20_000, seed=11)
    m = len(layout.self_pairs)
    d = np.concatenate([distances(layout.tree, Q[k : k + 5000])[:, :m] for k in range(0, 20_000, 5000)])
    never = {p for p, r in reasons.items() if r == "Never"}
    links_of = [tuple(sorted((shapes[i].link, shapes[j].link))) for i, j in layout.self_pairs]
    cols = [k for k, p in enumerate(links_of) if p in never]
    assert cols and d[:, cols].min() > 0
    # and some link pair left out does touch (the file does not disable everything)
    rest = [k for k in range(m) if k not in set(cols)]
    assert (d[:, rest] < 0).any()


def test_written_srdf_parses_as_srdfdom_reads_it_and_round_trips(panda):
    pairs = disabled_pairs(panda)
    text = write_srdf(panda.name, pairs)
    root = ET.fromstring(text.split("\n", 1)[1])  # the XML declaration line is standard
    assert text.startswith('<?xml version="1.0" encoding="UTF-8"?>')
    assert root.tag == "robot" and root.get("name") == "panda"
    rows = root.findall("disable_collisions")
    assert len(rows) == len(pairs) and all(set(r.attrib) == {"link1", "link2", "reason"} for r in rows)
    assert {(r.get("link1"), r.get("link2"), r.get("reason")) for r in rows} == set(pairs)
    assert read_srdf(text) == tuple((a, b) for a, b, _ in pairs)
    carriers = {x: (x,) for x in panda.geometry.links}
    disabled, partial, used = srdf_disabled(text, carriers)
    assert disabled == tuple((a, b) for a, b, _ in pairs) and partial == () and used == len(pairs)
    # the model with its SRDF checks fewer pairs and gives the same verdicts within the limits
    lean = panda.with_geometry(panda.geometry.with_disabled(disabled))
    assert len(layout_of(lean).self_pairs) < len(layout_of(panda).self_pairs)
    Q = panda.random_q(3000, seed=2)
    kin, lean_kin = symkin.compile(panda), symkin.compile(lean)
    assert np.array_equal(kin.in_collision(Q), lean_kin.in_collision(Q))


def test_names_are_escaped_and_the_comment_stays_a_comment():
    text = write_srdf('arm "A" & <B>', [("a&b", 'c"d', "Never")], note="a -- b")
    root = ET.fromstring(text.split("\n", 1)[1])
    assert root.get("name") == 'arm "A" & <B>'
    (row,) = root.findall("disable_collisions")
    assert (row.get("link1"), row.get("link2")) == ("a&b", 'c"d')


ARM = """<robot name="arm2">
  <link name="base_link"><collision><geometry><sphere radius="0.1"/></geometry></collision></link>
  <link name="l1"><collision><origin xyz="0 0 0.2"/><geometry><sphere radius="0.05"/></geometry>
    </collision></link>
  <link name="l2"><collision><origin xyz="0.3 0 0"/><geometry><sphere radius="0.05"/></geometry>
    </collision></link>
  <link name="hand"><collision><geometry><sphere radius="0.04"/></geometry></collision></link>
  <link name="finger"><collision><origin xyz="0.05 0 0"/><geometry><sphere radius="0.02"/></geometry>
    </collision></link>
  <link name="flange"><collision><geometry><sphere radius="0.03"/></geometry></collision></link>
  <joint name="j1" type="revolute"><parent link="base_link"/><child link="l1"/><origin xyz="0 0 0.1"/>
    <axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/><origin xyz="0 0 0.3"/>
    <axis xyz="0 1 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
  <joint name="j3" type="revolute"><parent link="l2"/><child link="flange"/><origin xyz="0.6 0 0"/>
    <axis xyz="1 0 0"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="fix1" type="fixed"><parent link="flange"/><child link="hand"/><origin xyz="0.05 0 0"/></joint>
  <joint name="fix2" type="fixed"><parent link="hand"/><child link="finger"/><origin xyz="0.05 0 0"/></joint>
</robot>"""


def test_urdf_names_carriers_and_the_conservative_reading(tmp_path):
    path = tmp_path / "arm2.urdf"
    path.write_text(ARM)
    robot = symkin.Robot.from_urdf(path)
    robot = robot.with_geometry(geometry_from_urdf(path, robot))
    carriers = urdf_carriers(path, robot)
    assert carriers == {
        "base": ("base_link",),
        "link1": ("l1",),
        "link2": ("l2",),
        "link3": ("hand", "flange"),
        "ee": ("finger",),
    }
    pairs = disabled_pairs(robot)
    text = write_srdf("arm2", pairs, carriers)
    rows = {(r.get("link1"), r.get("link2")): r.get("reason") for r in ET.fromstring(text.split("\n", 1)[1])}
    assert rows[("flange", "hand")] == "Adjacent"  # merged into one model link by fixed joints
    named = {x for p in rows for x in p}
    assert named == {"base_link", "l1", "l2", "flange", "hand", "finger"}  # URDF names
    # read back conservatively: the same model pairs
    disabled, partial, _ = srdf_disabled(text, carriers)
    assert disabled == tuple((a, b) for a, b, _ in pairs) and not partial
    # an SRDF that disables the hand against l1 but not the flange leaves (link1, link3) checked
    partial_srdf = '<robot name="arm2"><disable_collisions link1="hand" link2="l1" reason="Never"/></robot>'
    disabled, partial, used = srdf_disabled(partial_srdf, carriers)
    assert disabled == () and partial == (("link1", "link3"),) and used == 1
    # read_srdf with a mapping reads as conservatively: the pair stays checked, with a warning
    mapping = {ln: m for m, links in carriers.items() for ln in links}
    with pytest.warns(UserWarning, match=r"1 model link pairs stay checked.*\(link1, link3\)"):
        assert read_srdf(partial_srdf, mapping) == ()
    full = partial_srdf.replace("</robot>", '<disable_collisions link1="flange" link2="l1"/></robot>')
    assert read_srdf(full, mapping) == (("link1", "link3"),)


def test_a_model_without_geometry_has_no_srdf():
    with pytest.raises(GeometryError, match="no collision geometry"):
        disabled_pairs(symkin.load("puma560"))
    bare = symkin.load("planar3").with_geometry(Geometry((Sphere((0, 0, 0), 0.1, "base"),)))
    assert disabled_pairs(bare) == ()
