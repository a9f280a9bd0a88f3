"""Deprecated alias of :mod:`handeye.base.errors` (moved there by issue 39; goes in the next release)."""  # handeye-rooms-shim

from handeye.base import alias_module

alias_module(__name__, "handeye.base.errors")
