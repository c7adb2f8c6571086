"""Shared fixtures: the repository's sample files and the built-in model."""
import pathlib

import pytest

import deform

ROOT = pathlib.Path(__file__).resolve().parents[2]
SAMPLES = ROOT / "samples" / "data"


@pytest.fixture(scope="session")
def builtin_model():
    return deform.builtin_character()


@pytest.fixture
def model(builtin_model):
    return builtin_model.copy()


@pytest.fixture
def native_paths():
    return tuple(str(SAMPLES / f"builtin.{ext}") for ext in ("obj", "sk", "skw"))
