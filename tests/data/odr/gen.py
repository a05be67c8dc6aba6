#!/usr/bin/env python3
"""Writes curves.xodr (every geometry kind, chained end to end) for the
tests; the other files in this folder are written by hand. Run from the
repository root: python3 tests/data/odr/gen.py"""
import sys
import xml.etree.ElementTree as ET
sys.path.insert(0, "tests")
from odr_check import Geom

geoms = [
    ("line", {}, 20),
    ("spiral", {"curvStart": "0", "curvEnd": "0.02"}, 30),
    ("arc", {"curvature": "0.02"}, 40),
    ("spiral", {"curvStart": "0.02", "curvEnd": "-0.015"}, 30),
    ("poly3", {"a": "0", "b": "0", "c": "0.002", "d": "-0.00004"}, 30),
    ("paramPoly3", {"aU": "0", "bU": "1", "cU": "0", "dU": "0", "aV": "0", "bV": "0", "cV": "-0.004", "dV": "0.0001", "pRange": "arcLength"}, 30),
    ("paramPoly3", {"aU": "0", "bU": "30", "cU": "-1", "dU": "0", "aV": "0", "bV": "0", "cV": "4", "dV": "-2", "pRange": "normalized"}, 30),
]
x, y, h, s = 10.0, 60.0, 0.0, 0.0
out = []
for kind, attrs, length in geoms:
    a = " ".join(f'{k}="{v}"' for k, v in attrs.items())
    xml = f'<geometry s="{s!r}" x="{x!r}" y="{y!r}" hdg="{h!r}" length="{length}"><{kind} {a}/></geometry>'
    out.append("      " + xml)
    g = Geom(ET.fromstring(xml))
    x, y, h = g.eval(length)
    s += length
total = s
planview = "\n".join(out)
doc = f'''<?xml version="1.0" encoding="UTF-8"?>
<!-- Every planView geometry kind, laneOffset, three lane sections with
     changing widths (a taper opening a lane), and every road-mark type.
     Written by tests/data/odr/gen.py. -->
<OpenDRIVE>
  <header revMajor="1" revMinor="6" name="curves"/>
  <road name="curves" length="{total!r}" id="7" junction="-1">
    <planView>
{planview}
    </planView>
    <elevationProfile><elevation s="0" a="100" b="0.01" c="0" d="0"/></elevationProfile>
    <lanes>
      <laneOffset s="0" a="0" b="0" c="0" d="0"/>
      <laneOffset s="50" a="0" b="0" c="0.0006" d="-0.000008"/>
      <laneOffset s="100" a="0.5" b="0" c="0" d="0"/>
      <laneSection s="0">
        <left>
          <lane id="2" type="shoulder"><width sOffset="0" a="1" b="0" c="0" d="0"/>
            <roadMark sOffset="0" type="curb" width="0.15"/></lane>
          <lane id="1" type="driving"><width sOffset="0" a="3.5" b="0" c="0" d="0"/>
            <roadMark sOffset="0" type="solid broken" color="white" width="0.12"/></lane>
        </left>
        <center><lane id="0" type="none"><roadMark sOffset="0" type="broken" color="yellow" width="0.12"/></lane></center>
        <right>
          <lane id="-1" type="driving"><width sOffset="0" a="3.25" b="0" c="0.00025" d="-0.0000025"/>
            <roadMark sOffset="0" type="broken solid" width="0.12"/></lane>
          <lane id="-2" type="biking"><width sOffset="0" a="1.5" b="0" c="0" d="0"/>
            <roadMark sOffset="0" type="botts dots"/><roadMark sOffset="40" type="edge" weight="bold"/></lane>
        </right>
      </laneSection>
      <laneSection s="67.5">
        <left>
          <lane id="1" type="driving"><width sOffset="0" a="3.5" b="0" c="0" d="0"/>
            <roadMark sOffset="0" type="solid solid" color="yellow" weight="bold"/></lane>
        </left>
        <center><lane id="0" type="none"><roadMark sOffset="0" type="broken" color="yellow" width="0.12"/></lane></center>
        <right>
          <lane id="-1" type="driving"><width sOffset="0" a="3.75" b="0" c="0" d="0"/>
            <roadMark sOffset="0" type="broken broken" width="0.1"/></lane>
          <lane id="-2" type="driving"><width sOffset="0" a="0" b="0" c="0.0065625" d="-0.000109375"/>
            <width sOffset="40" a="3.5" b="0" c="0" d="0"/>
            <roadMark sOffset="0" type="edge"/><roadMark sOffset="50" type="grass"/></lane>
          <lane id="-3" type="sidewalk"><width sOffset="0" a="2" b="0" c="0" d="0"/>
            <roadMark sOffset="0" type="none"/></lane>
        </right>
      </laneSection>
      <laneSection s="141.25">
        <left>
          <lane id="1" type="driving"><width sOffset="0" a="3.5" b="0" c="0" d="0"/>
            <roadMark sOffset="0" type="solid" width="0.15"/></lane>
        </left>
        <center><lane id="0" type="none"><roadMark sOffset="0" type="broken" color="yellow" width="0.12"/></lane></center>
        <right>
          <lane id="-1" type="driving"><width sOffset="0" a="3.75" b="0" c="0" d="0"/>
            <roadMark sOffset="0" type="broken" width="0.12"/></lane>
          <lane id="-2" type="driving"><width sOffset="0" a="3.5" b="0" c="0" d="0"/>
            <roadMark sOffset="0" type="solid" width="0.25"/></lane>
        </right>
      </laneSection>
    </lanes>
  </road>
</OpenDRIVE>
'''
open("tests/data/odr/curves.xodr", "w").write(doc)
print("curves.xodr: length", total, "end", x, y)
