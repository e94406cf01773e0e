"""`Registry`: backends of one kind (clip generators, parsers...) by name, or by ``"module:factory"``.

Each kind keeps one registry next to its protocol (`generate.backends.GENERATORS`,
`language.backends.PARSERS`). A registered name maps to a factory, imported only when first
used (``"package.module:function"`` strings keep optional dependencies unimported); any other
name of the form ``"module:factory"`` imports `module` and calls its `factory`: it runs that
module's code, so name only code you trust.

    GENERATORS = Registry("generator", ClipGenerator)
    GENERATORS.register("procedural", "morphosim_gym.generate.procedural:make_procedural")
    generator = GENERATORS.create("procedural", config)

An unknown name raises `UnknownBackendError` listing the known ones; a ``"module:factory"``
whose module fails to import raises `BackendUnavailableError` naming the module and why.
"""

from __future__ import annotations

import importlib
import re
from collections.abc import Callable
from typing import Any, Generic, TypeVar, Union

from .errors import BackendUnavailableError, UnknownBackendError

__all__ = ["Registry", "is_factory_spec", "load_factory"]

T = TypeVar("T")
Factory = Callable[..., Any]
_SPEC = re.compile(r"^[A-Za-z_][\w.]*:[A-Za-z_]\w*$")


def is_factory_spec(name: str) -> bool:
    """Whether `name` has the form ``"module.path:factory"``."""
    return isinstance(name, str) and bool(_SPEC.match(name))


def load_factory(spec: str, kind: str = "backend") -> Factory:
    """The callable a ``"module:factory"`` spec names (imports the module)."""
    if not is_factory_spec(spec):
        raise UnknownBackendError(f"Expected a {kind} as 'module:factory', found {spec!r}")
    module_name, _, attr = spec.partition(":")
    try:
        module = importlib.import_module(module_name)
    except Exception as e:  # ImportError, or the module's own code failing
        raise BackendUnavailableError(f"Could not import module {module_name!r} of the {kind} {spec!r}: "
                                      f"{type(e).__name__}: {e}") from e
    factory = getattr(module, attr, None)
    if not callable(factory):
        raise UnknownBackendError(f"Expected module {module_name!r} to define a callable {attr!r} for the {kind} "
                                  f"{spec!r}, found {'nothing' if factory is None else type(factory).__name__}")
    return factory


class Registry(Generic[T]):
    """Named factories of one backend kind.

    Args:
        kind: what the backends are ("generator", "parser"), used in messages.
        protocol: a `typing.runtime_checkable` Protocol (or class) every created backend must
            satisfy; None: no check.
    """

    def __init__(self, kind: str, protocol: type | None = None) -> None:
        self.kind = kind
        self.protocol = protocol
        self._factories: dict[str, Union[str, Factory]] = {}

    def register(self, name: str, factory: Union[str, Factory], *, replace: bool = False) -> None:
        """Add a backend: `factory` is a callable or a lazy ``"module:function"`` string."""
        if not isinstance(name, str) or not name or ":" in name:
            raise ValueError(f"Expected a {self.kind} name without ':', found {name!r}")
        if name in self._factories and not replace:
            raise ValueError(f"Expected a new {self.kind} name, found {name!r} already registered")
        if not (callable(factory) or is_factory_spec(factory)):
            raise ValueError(f"Expected a callable or a 'module:function' string as the factory of {name!r}, "
                             f"found {factory!r}")
        self._factories[name] = factory

    def names(self) -> tuple[str, ...]:
        """The registered names, in registration order."""
        return tuple(self._factories)

    def known(self) -> str:
        """The known names as a message fragment."""
        return ", ".join(repr(n) for n in self._factories) + ", or 'module:factory'"

    def check(self, name: Any) -> str:
        """`name` if it is registered or a well-formed ``"module:factory"`` spec (nothing imported);
        else `UnknownBackendError` listing the known names."""
        if isinstance(name, str) and (name in self._factories or is_factory_spec(name)):
            return name
        raise UnknownBackendError(f"Unknown {self.kind} {name!r}; known: {self.known()}")

    def factory(self, name: str) -> Factory:
        """The factory of a name (a registered one, or a ``"module:factory"`` spec, imported now)."""
        entry = self._factories.get(self.check(name), name)
        return load_factory(entry, self.kind) if isinstance(entry, str) else entry

    def create(self, name: str, *args: Any, **kwargs: Any) -> T:
        """Build the backend `name` with the factory's arguments; checks it against the protocol."""
        backend = self.factory(name)(*args, **kwargs)
        if self.protocol is not None and not isinstance(backend, self.protocol):
            raise ValueError(f"Expected the {self.kind} {name!r} to implement {self.protocol.__name__}, found "
                            f"{type(backend).__name__}")
        return backend

    def __contains__(self, name: object) -> bool:
        return name in self._factories

    def __repr__(self) -> str:
        return f"Registry({self.kind!r}, {list(self._factories)})"
