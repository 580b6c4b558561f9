"""The ctypes mirrors of the C structs against the header: a C program compiled against
include/snakegrid.h prints each struct's size and each mirrored field's offset, and they must be
the ctypes ones. A field the header gains changes the size; a renamed one does not compile."""

import ctypes
import subprocess

from snakegrid import _abi

from conftest import HEADER


def test_struct_sizes_and_offsets_match_the_header(tmp_path):
    lines = ["#include <stddef.h>", "#include <stdio.h>", f'#include "{HEADER}"',
             "int main(void) {"]
    expected = []
    for c_name, struct in _abi.STRUCTS.items():
        lines.append(f'printf("{c_name} %zu\\n", sizeof(struct {c_name}));')
        expected.append(f"{c_name} {ctypes.sizeof(struct)}")
        for field, _ in struct._fields_:
            lines.append(
                f'printf("{c_name}.{field} %zu\\n", offsetof(struct {c_name}, {field}));')
            expected.append(f"{c_name}.{field} {getattr(struct, field).offset}")
    lines += ["return 0;", "}"]
    source = tmp_path / "layout.c"
    source.write_text("\n".join(lines))
    program = tmp_path / "layout"
    subprocess.run(["cc", "-std=c99", "-Wall", "-Werror", "-o", str(program), str(source)],
                   check=True)
    printed = subprocess.run([str(program)], check=True, capture_output=True,
                             text=True).stdout.split("\n")
    assert printed[:-1] == expected

