"""The extension's header (Python's and NumPy's API) is precompiled once per cache folder
(native.library.precompiled_header): the libraries compiled with it are the bytes of those
compiled with the header's text in place, a precompiled form cut short is made again, and a
compiler that makes none still compiles, reading the header."""

import stat

import pytest

from irb140_dynamics import native
from irb140_dynamics.core import irb140
from irb140_dynamics.core.codegen import c_code
from irb140_dynamics.core.codegen.kernels import kernels_of
from irb140_dynamics.native import compiler, library

pytestmark = pytest.mark.skipif(
    not compiler.enabled() or compiler.headers() is None, reason="no C compiler or Python.h"
)


def extension():
    """(source, flags) of the IRB-140's gravity kernel as an extension."""
    source = c_code.extension_source(kernels_of(irb140()).gravity_torques.program, "kheader")
    return source, [f"-I{folder}" for folder in compiler.headers()]


def header_folders() -> list:
    return sorted(p for p in native.cache_dir().iterdir() if p.name.startswith("header-"))


def test_a_library_compiled_with_the_precompiled_header_is_the_one_of_the_header_in_place(monkeypatch, tmp_path):
    monkeypatch.setenv("IRB140_CACHE", str(tmp_path))  # a cache of its own: the run's workers share theirs
    source, flags = extension()
    name, text = c_code.EXTENSION_HEADER
    made = library.library(source, flags, c_code.EXTENSION_HEADER)
    [folder] = header_folders()
    assert (folder / f"{name}.gch").stat().st_size > 0  # GCC's precompiled form, next to the header
    inline = library.library(source.replace(f'#include "{name}"\n', text), flags)
    assert made.read_bytes() == inline.read_bytes()
    library.library(source.replace("kheader", "kother"), flags, c_code.EXTENSION_HEADER)
    assert header_folders() == [folder]  # made once


def test_a_precompiled_header_cut_short_is_made_again(monkeypatch, tmp_path):
    monkeypatch.setenv("IRB140_CACHE", str(tmp_path))
    source, flags = extension()
    library.library(source, flags, c_code.EXTENSION_HEADER)
    [folder] = header_folders()
    precompiled = folder / f"{c_code.EXTENSION_HEADER[0]}.gch"
    whole = precompiled.read_bytes()
    precompiled.write_bytes(whole[: len(whole) // 2])
    library.library(source.replace("kheader", "kagain"), flags, c_code.EXTENSION_HEADER)
    [again] = header_folders()  # made again: of its size (not byte for byte: GCC's are not reproducible)
    size = (again / precompiled.name).stat().st_size
    assert size > len(whole) // 2 and again.name.endswith(f"-{size}")


def test_a_compiler_that_makes_no_precompiled_header_reads_the_header(monkeypatch, tmp_path):
    cc = tmp_path / "cc"
    cc.write_text(f'#!/bin/sh\ncase "$*" in *c-header*) exit 1;; esac\nexec {compiler.c_compiler()} "$@"\n')
    cc.chmod(cc.stat().st_mode | stat.S_IXUSR)
    monkeypatch.setenv("CC", str(cc))
    monkeypatch.setenv("IRB140_CACHE", str(tmp_path / "cache"))
    source, flags = extension()
    made = library.library(source, flags, c_code.EXTENSION_HEADER)
    assert header_folders() == [] and made.stat().st_size > 0  # the header read beside the source
