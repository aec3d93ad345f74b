"""Fixtures of the io tests."""

import sys
from pathlib import Path

import pytest

# Test modules import the helpers as ``io_factory`` whatever pytest's import mode.
sys.path.insert(0, str(Path(__file__).parent))

from io_factory import make_recording  # noqa: E402


@pytest.fixture
def recording():
    return make_recording()
