"""Shared paths: ctest sets TDCR_SOURCE_DIR and TDCR_CLI (tests/python.cmake)."""
import os
import pathlib

import pytest

SOURCE_DIR = pathlib.Path(os.environ.get("TDCR_SOURCE_DIR", pathlib.Path(__file__).resolve().parents[2]))
EXAMPLES = SOURCE_DIR / "examples"


@pytest.fixture
def paper_scene():
    import tdcr
    return tdcr.Scene.from_file(str(EXAMPLES / "paper_robot_vc.json"))


@pytest.fixture
def cli():
    path = os.environ.get("TDCR_CLI")
    if not path:
        pytest.skip("TDCR_CLI not set (run through ctest)")
    return path
