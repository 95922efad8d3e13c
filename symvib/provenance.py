"""Hashes that tie a generated kernel module to its inputs (no SymPy, no NumPy).

A module's input hash covers the curve's defining data (canonical JSON of its
expression texts, parameters, domain and hints) and the source code of the
symbolic wing that turns them into kernels.  Both wings compute it: the code
generator writes it into the module header, the numeric wing recomputes it to
find a cached user curve or to tell that a committed module is stale.

>>> h = input_hash({"kind": "graph", "z": "x**2", "q": "x"})
>>> len(h)
64
"""
from __future__ import annotations

import hashlib
import json
from functools import cache
from pathlib import Path

__all__ = ["GENERATOR_VERSION", "GENERATOR_SOURCES", "generator_digest", "input_hash", "JETS_SOURCES",
           "jets_hash"]

#: Bumped by hand when the kernel format changes in a way the sources do not show.
GENERATOR_VERSION = "2"
#: Modules whose code decides what a generated kernel module contains.
GENERATOR_SOURCES = ("symbolic/symbols.py", "expr.py", "symbolic/curve.py", "symbolic/branches.py",
                     "symbolic/identity.py", "symbolic/angle.py", "symbolic/integrals.py", "symbolic/derive.py",
                     "codegen/printers.py", "codegen/kernel_text.py", "codegen/generate.py", "antiderivative.py")
#: Modules whose code decides what a curve's jets module contains besides :data:`GENERATOR_SOURCES`
#: (kept apart so that the kernel modules' hash, and so ``generated/``, stay as they are).
JETS_SOURCES = ("codegen/jets.py",)


@cache
def generator_digest() -> str:
    """SHA-256 over the generator's own source files (line endings normalized)."""
    here = Path(__file__).resolve().parent
    digest = hashlib.sha256(GENERATOR_VERSION.encode())
    for name in GENERATOR_SOURCES:
        digest.update(name.encode())
        digest.update((here / name).read_bytes().replace(b"\r\n", b"\n"))
    return digest.hexdigest()


def input_hash(source: dict) -> str:
    """Hash of a curve's defining data together with :func:`generator_digest`."""
    canonical = json.dumps(source, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256((canonical + generator_digest()).encode()).hexdigest()


@cache
def _jets_digest() -> str:
    here = Path(__file__).resolve().parent
    digest = hashlib.sha256()
    for name in JETS_SOURCES:
        digest.update(name.encode())
        digest.update((here / name).read_bytes().replace(b"\r\n", b"\n"))
    return digest.hexdigest()


def jets_hash(source: dict) -> str:
    """Hash of a curve's jets module (:mod:`symvib.codegen.jets`): its kernel module's
    :func:`input_hash` together with the jets generator's source."""
    return hashlib.sha256(("jets:" + input_hash(source) + _jets_digest()).encode()).hexdigest()
