"""deform.Error carries libdeform's message and where it happened."""
import numpy as np
import pytest

import deform


def test_error_is_a_value_error():
    assert issubclass(deform.Error, ValueError)


def test_missing_file_names_the_file(tmp_path, native_paths):
    missing = str(tmp_path / "missing.obj")
    with pytest.raises(deform.Error) as info:
        deform.load_model(missing, native_paths[1], native_paths[2])
    assert info.value.file == missing
    assert info.value.kind == "input"
    assert str(info.value).startswith(missing + ": ")


def test_text_error_has_file_line_and_element(tmp_path, native_paths):
    obj = tmp_path / "bad.obj"
    obj.write_text("v 0 0 0\nf 1 2 3\n")
    with pytest.raises(deform.Error) as info:
        deform.load_model(str(obj), native_paths[1], native_paths[2])
    e = info.value
    assert (e.file, e.line, e.byte) == (str(obj), 2, None)
    assert e.element == "f corner 2"
    assert str(e) == f"{obj}: line 2: f corner 2: {e.message}"


def test_binary_error_has_byte_offset(tmp_path, native_paths):
    sk = tmp_path / "bad.sk"
    sk.write_bytes(b"SK\0garbage")
    with pytest.raises(deform.Error) as info:
        deform.load_model(native_paths[0], str(sk), native_paths[2])
    assert (info.value.file, info.value.byte, info.value.line) == (str(sk), 0, None)
    assert "magic" in info.value.message


def test_invalid_argument_names_the_element():
    skeleton = deform.builtin_character().skeleton
    with pytest.raises(deform.Error) as info:
        skeleton.limits("no_such_bone")
    assert info.value.kind == "argument"
    assert info.value.file is None
    assert info.value.element == "bone 'no_such_bone'"


def test_refused_per_frame_call_raises_its_reason():
    rest = np.zeros((4, 3), np.float32)
    lattice = deform.ElasticLattice(rest)
    with pytest.raises(deform.Error) as info:
        lattice.step(1 / 60, np.zeros((5, 3), np.float32))
    assert info.value.kind == "status"
    assert info.value.message == str(info.value)
    assert info.value.message
    character = deform.Character.builtin()
    with pytest.raises(deform.Error) as info:
        character.update(-1.0)
    assert info.value.kind == "status"


def test_wrong_shape_is_an_argument_error():
    with pytest.raises(deform.Error, match="shape"):
        deform.BezierLattice.around(np.zeros((4, 2), np.float32))
