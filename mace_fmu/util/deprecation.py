"""Renamed keywords keep working for a while: the old name is mapped onto the new one with a
DeprecationWarning that names both, so a user's script runs and says what to change."""

from __future__ import annotations

import functools
import warnings
from typing import Any, Callable, TypeVar

F = TypeVar("F", bound=Callable[..., Any])


def renamed_keyword(*, old: str, new: str) -> Callable[[F], F]:
    """Decorator: accept ``old=`` as the deprecated spelling of ``new=``.

    Parameters
    ----------
    old : str
        The keyword's earlier name.
    new : str
        Its name now.

    Returns
    -------
    callable
        A decorator. Giving both names in one call is a ``TypeError``; giving the old one alone warns
        (``DeprecationWarning``, pointing at the caller's line) and passes the value on as ``new``.

    Examples
    --------
    >>> import warnings
    >>> @renamed_keyword(old="structure", new="configuration")
    ... def f(*, configuration="1g"):
    ...     return configuration
    >>> with warnings.catch_warnings(record=True) as caught:
    ...     warnings.simplefilter("always")
    ...     f(structure="0g"), str(caught[0].message)
    ('0g', 'f(structure=...) is now f(configuration=...); the old name will be removed')
    """
    def decorate(func: F) -> F:
        @functools.wraps(func)
        def wrapper(*args: Any, **kwargs: Any) -> Any:
            if old in kwargs:
                name = func.__qualname__.replace(".__init__", "")
                if new in kwargs:
                    raise TypeError(f"{name}: give {new}= only ({old}= is its earlier name)")
                warnings.warn(f"{name}({old}=...) is now {name}({new}=...); the old name will be removed",
                              DeprecationWarning, stacklevel=2)
                kwargs[new] = kwargs.pop(old)
            return func(*args, **kwargs)
        return wrapper  # type: ignore[return-value]
    return decorate
