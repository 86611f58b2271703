"""Which module made a refused read (desmon.errors.reading_module): the innermost frame of
the refusal's traceback that is not a helper reading on its caller's behalf. The table
engine and an isolated deployer's worker both name the reader so."""

import types

from desmon.errors import reading_module


def _traceback_through(*modules: str):  # type: ignore[no-untyped-def]
    """The traceback of an error raised in the last of ``modules``, each called by the one before."""
    inner = None
    for name in reversed(modules):
        mod = types.ModuleType(name)
        mod.inner = inner  # type: ignore[attr-defined]
        exec("def call():\n    if inner is None:\n        raise LookupError('read')\n    return inner()\n", mod.__dict__)
        inner = mod.call  # type: ignore[attr-defined]
    try:
        inner()  # type: ignore[misc]
    except LookupError as exc:
        return exc.__traceback__.tb_next  # (from the first module's frame on)
    raise AssertionError("no error raised")


def test_the_reader_is_the_innermost_module_that_is_not_a_helper():
    tb = _traceback_through("my_deployer", "copy", "logging.handlers")
    assert reading_module(tb, ("copy", "logging")) == "my_deployer"


def test_a_module_whose_name_only_begins_like_a_helper_is_the_reader():
    # "copycat_deployer" and "logging_peek" are the user's modules, not copy's or logging's
    assert reading_module(_traceback_through("outer", "copycat_deployer", "copy"), ("copy",)) == "copycat_deployer"
    assert reading_module(_traceback_through("outer", "logging_peek"), ("logging",)) == "logging_peek"


def test_a_package_named_as_a_helper_covers_its_modules():
    tb = _traceback_through("user_code", "desmon.deployment.ports", "desmon.model.system")
    assert reading_module(tb, ("desmon",)) == "user_code"
