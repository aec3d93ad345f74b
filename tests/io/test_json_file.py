"""The viewer's JSON reader: every way a file can fail to parse is one InputError line naming the file."""

import pytest

from evpose.errors import InputError
from evpose.io.json_file import read_json


@pytest.mark.parametrize("text, needle", [
    ("{", "not valid JSON"),
    ('{"t_us": ' + "9" * 5000 + "}", "a number of more than 4300 digits"),  # was a bare ValueError
    ("[" * 100_000 + "]" * 100_000, "nested too deep"),  # was a RecursionError
])
def test_a_file_that_does_not_parse_is_one_line_naming_it(tmp_path, text, needle):
    path = tmp_path / "x.json"
    path.write_text(text)
    with pytest.raises(InputError, match=needle) as info:
        read_json(path)
    assert str(info.value).startswith(str(path)) and "\n" not in str(info.value)
