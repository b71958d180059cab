"""A reader of CCSDS Attitude Ephemeris Messages written from the standard's text (CCSDS
504.0-B-2, Attitude Data Messages, §4 and annex F; the XML form per CCSDS 505.0-B-3's
NDM/XML schemas, unqualified), independent of the library agilesat writes them with: the
tests read our AEMs back through it.  No Python library other than the writer reads AEM
version 2.0 (``ccsds-ndm``, the other, installs into the same package name and is
GPL-licensed).

KVN (§4.2, §7): ``KEYWORD = value`` lines; the header before ``META_START``; each
segment a metadata block ``META_START`` … ``META_STOP`` and a data block ``DATA_START`` …
``DATA_STOP`` whose lines are an epoch then the attitude's numbers, in the order of table
4-4 for the ATTITUDE_TYPE (QUATERNION/ANGVEL: Q1 Q2 Q3 QC ANGVEL_X ANGVEL_Y ANGVEL_Z);
``COMMENT`` lines anywhere a comment may be; blank lines ignored.

XML: ``<aem>`` ``<header>`` ``<body>`` ``<segment>`` ``<metadata>`` (the KVN keywords as
elements) ``<data>`` ``<attitudeState>`` ``<quaternionAngVel>`` (``EPOCH``,
``<quaternion>`` Q1…QC, ``<angVel>`` ANGVEL_X…Z).
"""

from __future__ import annotations

import datetime

import numpy as np
from lxml import etree

COLUMNS = {
    "QUATERNION": ("Q1", "Q2", "Q3", "QC"),
    "QUATERNION/ANGVEL": ("Q1", "Q2", "Q3", "QC", "ANGVEL_X", "ANGVEL_Y", "ANGVEL_Z"),
}


def epoch(text: str) -> datetime.datetime:
    """An ADM epoch in calendar form, YYYY-MM-DDThh:mm:ss[.d…] (§7.5.10)."""
    text = text.strip().rstrip("Z")
    whole, _, fraction = text.partition(".")
    stamp = datetime.datetime.strptime(whole, "%Y-%m-%dT%H:%M:%S")
    return stamp + datetime.timedelta(microseconds=round(float(f"0.{fraction or 0}") * 1e6))


def read_kvn(text: str) -> dict:
    """{"header": {...}, "segments": [{"metadata": {...}, "epochs": [...], "data": (n, k)}]}"""
    header: dict = {}
    segments: list = []
    block = header
    rows: list = []
    state = "header"
    for raw in text.splitlines():
        line = raw.strip()
        if not line or line.startswith("COMMENT"):
            continue
        if line == "META_START":
            segments.append({"metadata": {}, "epochs": [], "data": []})
            block, state = segments[-1]["metadata"], "metadata"
        elif line == "META_STOP":
            state = "between"
        elif line == "DATA_START":
            state, rows = "data", segments[-1]["data"]
        elif line == "DATA_STOP":
            state = "between"
        elif state == "data":
            fields = line.split()
            segments[-1]["epochs"].append(epoch(fields[0]))
            rows.append([float(x) for x in fields[1:]])
        else:
            keyword, equals, value = line.partition("=")
            if not equals:
                raise ValueError(f"not a KVN line: {raw!r}")
            block[keyword.strip()] = value.strip()
    for segment in segments:
        segment["data"] = np.array(segment["data"], float)
    return {"header": header, "segments": segments}


def read_xml(text: str) -> dict:
    """The same structure from the XML form."""
    root = etree.fromstring(text.encode())
    if etree.QName(root).localname != "aem":
        raise ValueError(f"not an AEM: <{root.tag}>")
    header = {e.tag: e.text for e in root.find("header") if isinstance(e.tag, str)}
    header["CCSDS_AEM_VERS"] = root.get("version")
    segments = []
    for segment in root.find("body").findall("segment"):
        metadata = {
            e.tag: (e.text or "").strip()
            for e in segment.find("metadata")
            if isinstance(e.tag, str) and e.tag != "COMMENT"
        }
        names = COLUMNS[metadata["ATTITUDE_TYPE"]]
        epochs, rows = [], []
        for state in segment.find("data").findall("attitudeState"):
            (kind,) = [e for e in state if isinstance(e.tag, str)]
            epochs.append(epoch(kind.findtext("EPOCH")))
            rows.append([float(kind.find(f".//{name}").text) for name in names])
        segments.append({"metadata": metadata, "epochs": epochs, "data": np.array(rows)})
    return {"header": header, "segments": segments}


def rotate_a_to_b(q1, q2, q3, qc, v_a) -> np.ndarray:
    """The coordinates in frame B of a vector with coordinates ``v_a`` in frame A, the AEM
    quaternion being the transformation from A to B: B is A turned by φ about the unit axis
    e, (Q1, Q2, Q3) = e sin(φ/2), QC = cos(φ/2) (annex F).  A frame turned by +φ sees a
    fixed vector turned by −φ (Rodrigues): v_b = v cos φ − (e × v) sin φ + e (e·v)(1 − cos φ)."""
    vector = np.array([q1, q2, q3], float)
    s = np.linalg.norm(vector)
    if s == 0:
        return np.asarray(v_a, float)
    e, phi = vector / s, 2 * np.arctan2(s, qc)
    v = np.asarray(v_a, float)
    return v * np.cos(phi) - np.cross(e, v) * np.sin(phi) + e * (e @ v) * (1 - np.cos(phi))
