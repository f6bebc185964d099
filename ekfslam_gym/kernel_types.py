"""The compiled kernels' argument types, written as annotations on the kernels themselves, and the numba
signature each kernel's annotations give (``numba_signature``), which the ahead-of-time build exports.

A kernel is annotated with Python's scalars (``float`` for float64, ``int`` for int64, ``bool``), the array
aliases below (their dtype, their number of dimensions, C-contiguous) and ``tuple[...]`` of these; ``None`` as
the return type is numba's ``void``. A kernel module may name a bundle of them with a string alias,
``FilterArrays: TypeAlias = "tuple[F8Array1, F8Array2]"``, read from the kernel's module. The annotations are read as written (every kernel module has
``from __future__ import annotations``), so a kernel's signature lives beside its parameters and is never
typed twice.

Loads no numba: the build and the tests read the signatures; ``ekfslam_gym.compiled`` does not need them.
"""

from __future__ import annotations

import ast
import inspect
from collections.abc import Callable, Mapping
from typing import Any, TypeAlias

import numpy as np

F8Array1: TypeAlias = np.ndarray  # float64 (n,), C-contiguous
F8Array2: TypeAlias = np.ndarray  # float64 (n, m), C-contiguous
F8Array3: TypeAlias = np.ndarray  # float64 (n, m, k), C-contiguous
F4Array1: TypeAlias = np.ndarray  # float32 (n,), C-contiguous
I8Array1: TypeAlias = np.ndarray  # int64 (n,), C-contiguous
BoolArray1: TypeAlias = np.ndarray  # bool (n,), C-contiguous
BoolArray2: TypeAlias = np.ndarray  # bool (n, m), C-contiguous

# Annotation name -> numba type, as numba's signature strings spell it.
NUMBA_TYPES: dict[str, str] = {
    "float": "f8",
    "int": "i8",
    "bool": "b1",
    "F8Array1": "f8[::1]",
    "F8Array2": "f8[:, ::1]",
    "F8Array3": "f8[:, :, ::1]",
    "F4Array1": "f4[::1]",
    "I8Array1": "i8[::1]",
    "BoolArray1": "b1[::1]",
    "BoolArray2": "b1[:, ::1]",
}


def numba_type(annotation: str, where: str = "annotation", aliases: Mapping[str, Any] | None = None) -> str:
    """The numba type of one annotation: a name of ``NUMBA_TYPES``, a ``tuple[...]`` of annotations, or a name
    that ``aliases`` (a kernel module's globals) binds to such an annotation as a string."""
    return _convert(ast.parse(annotation, mode="eval").body, annotation, where, aliases or {})


def _convert(node: ast.expr, text: str, where: str, aliases: Mapping[str, Any]) -> str:
    if isinstance(node, ast.Name) and node.id in NUMBA_TYPES:
        return NUMBA_TYPES[node.id]
    if isinstance(node, ast.Name) and isinstance(aliases.get(node.id), str):
        return numba_type(aliases[node.id], f"{where} ({node.id})", aliases)
    if isinstance(node, ast.Subscript) and isinstance(node.value, ast.Name) and node.value.id == "tuple":
        items = node.slice.elts if isinstance(node.slice, ast.Tuple) else [node.slice]
        inner = ", ".join(_convert(item, text, where, aliases) for item in items)
        return f"Tuple(({inner}))" if len(items) > 1 else f"Tuple(({inner},))"
    raise TypeError(
        f"{where}: {text!r} is not a kernel type; use {sorted(NUMBA_TYPES)} or tuple[...] of them"
    )


def numba_signature(function: Callable[..., Any]) -> str:
    """``function``'s numba signature from its annotations, e.g. ``Tuple((f8, i8))(f8[::1], i8)``.

    Every parameter and the return must be annotated (``-> None`` for none); positional parameters only."""
    function = getattr(function, "py_func", function)  # a numba dispatcher's Python function
    name = f"{function.__module__}.{function.__qualname__}"
    annotations = function.__annotations__
    if not all(isinstance(value, str) for value in annotations.values()):
        raise TypeError(f"{name}: annotations must be read as written (from __future__ import annotations)")
    arguments = []
    for parameter in inspect.signature(function).parameters.values():
        if parameter.kind not in (parameter.POSITIONAL_ONLY, parameter.POSITIONAL_OR_KEYWORD):
            raise TypeError(
                f"{name}: parameter {parameter.name!r} must be positional (the kernels' calls are)"
            )
        if parameter.name not in annotations:
            raise TypeError(f"{name}: parameter {parameter.name!r} has no annotation")
        where = f"{name}({parameter.name})"
        arguments.append(numba_type(annotations[parameter.name], where, function.__globals__))
    if "return" not in annotations:
        raise TypeError(f"{name}: the return type has no annotation (-> None for none)")
    returned = annotations["return"]
    result = "void" if returned == "None" else numba_type(returned, f"{name} return", function.__globals__)
    return f"{result}({', '.join(arguments)})"
