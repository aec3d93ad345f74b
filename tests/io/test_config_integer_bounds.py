"""An integer setting is a 64-bit integer, whether or not its field declares a range."""

import pytest

from evpose.errors import InputError
from evpose.io.config_file import read_config


@pytest.mark.parametrize("value, shown", [("1e300", "'1e300'"), ("1.0e+300", "1e+300"), (str(2**70), str(2**70)),
                                          (str(-(2**63) - 1), str(-(2**63) - 1))])
def test_an_integer_too_large_for_64_bits_is_named_in_one_line(tmp_path, value, shown):
    # SlamConfig.seed declares no range: 1e300 (text to YAML, a number to JSON) reached numpy's seeding as "OverflowError: Python int too large to
    # convert to C long", a traceback out of `evpose slam --config`.
    from evpose.slam.config import SlamConfig

    path = tmp_path / "slam.yaml"
    path.write_text(f"seed: {value}\n")
    with pytest.raises(InputError) as info:
        read_config(SlamConfig, path)
    assert str(info.value) == f"{path}: seed: expected an integer that fits in 64 bits, got {shown}"


def test_large_integers_that_fit_keep_every_digit(tmp_path):
    from evpose.slam.config import SlamConfig

    path = tmp_path / "slam.yaml"
    path.write_text(f"seed: {2**62 + 1}\n")  # through float() it became 2**62
    assert read_config(SlamConfig, path).seed == 2**62 + 1


def test_slam_with_such_a_config_exits_2_before_reading_the_recording(tmp_path, capsys):
    from evpose.cli.main import run

    cfg = tmp_path / "slam.yaml"
    cfg.write_text("seed: 1e300\n")
    rec = tmp_path / "rec.h5"
    rec.write_bytes(b"not read: the config is refused first")
    assert run(["slam", str(rec), "--out", str(tmp_path / "est.txt"), "--config", str(cfg)]) == 2
    err = capsys.readouterr().err
    assert err == f"evpose slam: error: {cfg}: seed: expected an integer that fits in 64 bits, got '1e300'\n"
