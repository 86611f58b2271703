"""The wire between desmon and a deployer's worker process: messages, and what may cross.

Each message is a pickle, framed by its length. desmon's side writes plain data and
frozen records by value and any other object as a handle (:class:`Encoder`); it reads the
child's messages with :class:`Decoder`, which builds nothing but plain data, frozen
records of desmon's (or of a requirement kind a scenario registered) and the handles it
gave out. The child trusts desmon and reads with pickle's own rules, answering handles
with its proxies (:mod:`desmon.verify.isolation.child`).
"""

from __future__ import annotations

import dataclasses
import functools
import io
import pickle
import pickletools
import socket
import struct
import sys
import types
from typing import Any

from desmon.deployment.ports import PlatformHandle, Validity

__all__ = [
    "send_message", "recv_message", "recv_exact", "Encoder", "Decoder", "Handles", "Handle", "Method", "DefaultChecks", "DEFAULT",
    "Blob", "BLOBS", "Token", "resolve", "plain_class", "one_line", "encode", "handle", "MAX_MESSAGE", "MAX_NODES", "Resolve", "weight", "SHARING", "shared_opcode",
]
HEADER = struct.Struct("!I")
#: the largest message either side accepts (a deployer cannot make desmon allocate more)
MAX_MESSAGE = 64 << 20


def plain_class(cls: type) -> bool:
    """Whether instances of ``cls`` cross by value: desmon's frozen records (and those of a kind a scenario registered)."""
    params = cls.__dict__.get("__dataclass_params__")  # (a subclass that is not a dataclass of its own is not plain)
    return params is not None and params.frozen


SCALARS = (type(None), bool, int, float, complex, str, bytes)
CONTAINERS = (tuple, list, frozenset, set, dict)
BY_NAME = (types.FunctionType, types.BuiltinFunctionType)


def role_of(obj: object) -> str:
    if isinstance(obj, PlatformHandle):
        return "state"
    if isinstance(obj, Validity):
        return "validity"
    return "object"


def send_message(sock: socket.socket, data: bytes) -> None:
    if len(data) > MAX_MESSAGE:
        raise ValueError(f"a message of {len(data):,} bytes, more than {MAX_MESSAGE:,}")
    sock.sendall(HEADER.pack(len(data)) + data)


def recv_exact(sock: socket.socket, n: int) -> bytes:
    chunks, left = [], n
    while left:
        chunk = sock.recv(min(left, 1 << 20))
        if not chunk:
            raise EOFError("the conversation ended")
        chunks.append(chunk)
        left -= len(chunk)
    return b"".join(chunks)


def recv_message(sock: socket.socket, pending: bytearray | None = None) -> bytes:
    """One message. Without ``pending`` the conversation is turn by turn (nothing follows a
    message until this side answers); with it, the peer may send several in a row: it
    holds what was received past the last message, and keeps what follows this one."""
    if pending is not None:
        return _buffered(sock, pending)
    first = sock.recv(1 << 16)
    if not first:
        raise EOFError("the conversation ended")
    if len(first) < HEADER.size:
        first += recv_exact(sock, HEADER.size - len(first))
    (n,) = HEADER.unpack_from(first)
    if n > MAX_MESSAGE:
        raise ValueError(f"a message of {n:,} bytes, more than {MAX_MESSAGE:,}")
    body = first[HEADER.size:]
    return body if len(body) >= n else body + recv_exact(sock, n - len(body))


def _buffered(sock: socket.socket, pending: bytearray) -> bytes:
    while len(pending) < HEADER.size:
        _fill(sock, pending, HEADER.size - len(pending))
    (n,) = HEADER.unpack_from(pending)
    if n > MAX_MESSAGE:
        raise ValueError(f"a message of {n:,} bytes, more than {MAX_MESSAGE:,}")
    end = HEADER.size + n
    while len(pending) < end:
        _fill(sock, pending, end - len(pending))
    body = bytes(memoryview(pending)[HEADER.size:end])
    del pending[:end]
    return body


def _fill(sock: socket.socket, pending: bytearray, missing: int) -> None:
    chunk = sock.recv(max(1 << 16, min(missing, 1 << 20)))
    if not chunk:
        raise EOFError("the conversation ended")
    pending += chunk


class Encoder(pickle.Pickler):
    """desmon's side: plain data and frozen records by value, anything else as a handle in
    ``handles`` (written as a call of :func:`handle`, which the child's decoder answers
    with its proxy). ``plain``: the worker's memo of which classes are plain."""

    def __init__(self, out: io.BytesIO, handles: "Handles", plain: dict[type, bool]) -> None:
        super().__init__(out, protocol=5)
        self.handles, self.plain = handles, plain

    def reducer_override(self, obj: Any) -> Any:  # (pickle calls it for no builtin scalar or container)
        kind = type(obj)
        plain = self.plain.get(kind)
        if plain is None:
            plain = self.plain[kind] = plain_class(kind) or issubclass(kind, type) or kind is complex
        if plain or (kind in BY_NAME and "<" not in obj.__qualname__):
            return NotImplemented  # (a record by value, a class or a module's function by its name)
        if kind is Handle:
            return handle, self.handles.give(obj.obj, obj.role)
        n, role = self.handles.give(obj)
        if kind is PlatformHandle:  # (what a reaction may read of it freely, and that never changes: sent with it)
            return handle, (n, role, {"platform": obj.platform, "deployed": obj.deployed, "name": obj.platform.name})
        return handle, (n, role)


def handle(n: int, role: str, fields: dict | None = None) -> Any:  # pragma: no cover - never called: the child's decoder answers it
    raise pickle.UnpicklingError("a handle outside a conversation")


class Decoder(pickle.Unpickler):
    """desmon's side, reading the child: plain data, frozen records of desmon's (or of a
    registered kind's) classes, and handles desmon gave out; nothing else is built."""

    def __init__(self, data: bytes, handles: "Handles") -> None:
        super().__init__(io.BytesIO(data))
        self.data, self.handles = data, handles

    def find_class(self, module: str, name: str) -> Any:
        if module == "builtins" and name in ("frozenset", "set", "complex"):
            return {"frozenset": frozenset, "set": set, "complex": complex}[name]
        found = sys.modules.get(module)
        cls = getattr(found, name, None) if found is not None and "." not in name else None
        if isinstance(cls, type) and plain_class(cls) and (module.startswith("desmon.") or registered(cls)):
            return cls
        raise pickle.UnpicklingError(f"{module}.{name} is not data desmon accepts from a deployer")

    def persistent_load(self, pid: Any) -> Any:
        self.handles.take(pid)  # (refused here where it is not one of this reaction's)
        return Token(pid[0])  # (inert: what the pickle does to it -- BUILD, REDUCE, APPENDS, SETITEMS -- reaches no object of desmon's)

    def load(self) -> Any:
        """The message, each handle in it (a :class:`Token` while it was read) the object desmon
        gave out. It holds no object twice (:data:`SHARING`): the child writes each where it
        occurs (its pickler's ``fast`` mode), so what desmon hashes or compares of it is no
        larger than the message."""
        shared, numbers = scan(self.data)
        if shared is not None:
            raise pickle.UnpicklingError(f"an object written once and used again ({shared}): the child writes each where it occurs")
        if numbers > MAX_NUMBERS:  # (before the C code builds it: nothing stops that code, not even desmon's timer)
            raise pickle.UnpicklingError(
                f"a message of {numbers:,} numbers, more than the {MAX_NUMBERS:,} desmon reads in one (numbers chosen to hash "
                "alike would make building a set or dict of them take hours)"
            )
        return resolve(super().load(), self.handles)


#: the opcodes that use an object again (a few nest into more than desmon could hash in a lifetime)
SHARING = frozenset({"GET", "BINGET", "LONG_BINGET", "DUP"})
#: the opcodes that build a number (ints and floats may be chosen to hash alike; texts may not)
NUMBERS = frozenset({"INT", "BININT", "BININT1", "BININT2", "LONG", "LONG1", "LONG4", "FLOAT", "BINFLOAT"})
#: the most numbers a message of the child's may hold: a deployer's commands and questions
#: hold a few dozen; 4,096 keys that hash alike take desmon's C decoder a fraction of a second
MAX_NUMBERS = 4096

#: how :func:`shared_opcode` passes an opcode: a fixed number of argument bytes; a length of 1
#: byte, of 4 or 8 bytes (unsigned) or of 4 bytes (signed) before them; the end; one of
#: :data:`SHARING`; an argument up to a newline (protocols 0 and 1: left to pickletools)
_FIXED, _SHORT, _LONG, _SIGNED, _STOP, _SHARES, _LINE = range(7)
_LENGTHS = {
    pickletools.TAKEN_FROM_ARGUMENT1: (_SHORT, 1), pickletools.TAKEN_FROM_ARGUMENT4: (_SIGNED, 4),
    pickletools.TAKEN_FROM_ARGUMENT4U: (_LONG, 4), pickletools.TAKEN_FROM_ARGUMENT8U: (_LONG, 8),
}


def _pass(op: pickletools.OpcodeInfo) -> tuple[int, int, bool, str]:
    """(how, bytes, whether the bytes are UTF-8 text, name) of one opcode (:data:`_OPCODES`)."""
    arg = op.arg
    n = 0 if arg is None else arg.n
    if n == pickletools.UP_TO_NEWLINE:  # (GET among them)
        return _LINE, 0, False, op.name
    if op.name in SHARING or op.name == "STOP":
        return (_SHARES if op.name in SHARING else _STOP), n, False, op.name
    if n >= 0:
        return _FIXED, n, False, op.name
    how, size = _LENGTHS[n]
    return how, size, arg.name.startswith("unicodestring"), op.name  # type: ignore[union-attr]


#: every opcode byte's :func:`_pass` (None: no opcode)
_OPCODES: tuple[tuple[int, int, bool, str] | None, ...] = tuple(
    map({op.code.encode("latin-1")[0]: _pass(op) for op in pickletools.opcodes}.get, range(256))
)


def shared_opcode(data: bytes) -> str | None:
    """The name of the first opcode of the pickle ``data`` (up to its STOP) that uses an object
    again (:data:`SHARING`), or None (:func:`scan`)."""
    return scan(data)[0]


def scan(data: bytes) -> tuple[str | None, int]:
    """The name of the first opcode of the pickle ``data`` (up to its STOP) that uses an object
    again (:data:`SHARING`), or None, and how many numbers it builds before (:data:`NUMBERS`):
    :func:`pickletools.genops`' answers. One pass over the opcodes, each argument skipped by
    its length (a text decoded, as genops does); where that cannot tell (an argument up to a
    newline, bytes that are no pickle), genops reads them, and raises what it raises."""
    found, numbers = _skim(data)
    if found is not _UNSURE:
        return found, numbers
    numbers = 0
    for op, _arg, _at in pickletools.genops(data):
        if op.name in SHARING:
            return op.name, numbers
        numbers += op.name in NUMBERS
    return None, numbers


#: :func:`_skim`'s answer where it cannot tell
_UNSURE = "?"


def _skim(data: bytes) -> tuple[str | None, int]:
    """:func:`scan`'s answer for a binary pickle, :data:`_UNSURE` first where it cannot tell."""
    i, end, table, numbers = 0, len(data), _OPCODES, 0
    while i < end:
        entry = table[data[i]]
        if entry is None:
            return _UNSURE, numbers
        how, n, text, name = entry
        numbers += name in NUMBERS
        i += 1
        if how == _FIXED:
            i += n
        elif how <= _SIGNED:  # a length, then that many bytes
            size = data[i] if how == _SHORT and i < end else int.from_bytes(data[i:i + n], "little", signed=how == _SIGNED)
            i += n
            if i > end or size < 0 or i + size > end:
                return _UNSURE, numbers
            if text:
                try:
                    str(data[i:i + size], "utf-8", "surrogatepass")
                except UnicodeDecodeError:
                    return _UNSURE, numbers
            i += size
        elif how == _SHARES:
            return (name if i + n <= end else _UNSURE), numbers
        else:
            return (None if how == _STOP else _UNSURE), numbers
    return _UNSURE, numbers

class Token:
    """A handle while the child's pickle is read: it can be neither called nor built nor
    added to, so the pickle's opcodes touch none of desmon's objects (:func:`resolve`
    puts the objects in place once the message is read)."""

    __slots__ = ("n",)

    def __init__(self, n: int) -> None:
        self.n = n

    def __setstate__(self, state: Any) -> None:
        raise pickle.UnpicklingError("a handle is not built")


#: the most objects a message of the child's may hold, each shared one counted as often as it is
#: reached (a few shared tuples nest into more than desmon could hash or compare in a lifetime;
#: a long text or number counts as many: :func:`weight`)
MAX_NODES = 1 << 20


def resolve(obj: Any, handles: "Handles") -> Any:
    """``obj`` with each :class:`Token` in it (in containers and in the records the message
    built) replaced by the object desmon gave out. A message that
    unfolds into more than :data:`MAX_NODES` objects, or nests deeper than Python recurses,
    is refused."""
    walk = Resolve(handles)
    out = walk(obj)
    if walk.sizes.get(id(obj), 1) > MAX_NODES:
        raise pickle.UnpicklingError(f"a message of more than {MAX_NODES:,} objects (unfolded)")
    return out


def weight(obj: Any) -> int:
    """What a scalar counts for in :data:`MAX_NODES`: a long text or number as many objects as
    its length in 256s of bytes (shared, it is hashed, compared and printed as often as reached)."""
    kind = type(obj)
    if kind in (str, bytes):
        return 1 + len(obj) // 256
    return 1 + obj.bit_length() // 2048 if kind is int else 1


class Resolve:
    """:func:`resolve`'s walk: ``done`` the containers and records met (a message may share
    or nest them) as (object, how many objects it unfolds into), by identity."""

    def __init__(self, handles: "Handles") -> None:
        self.handles = handles
        self.done: dict[int, Any] = {}
        self.sizes: dict[int, int] = {}
        self.keep: list[Any] = []  # (the objects met stay alive: their ids stay theirs)

    def __call__(self, obj: Any) -> Any:
        kind = type(obj)
        if kind is Token:
            return self.handles.take((obj.n, None))
        if kind in SCALARS or kind is type or kind in BY_NAME:
            return obj
        key = id(obj)
        if key in self.done:
            return self.done[key]
        self.keep.append(obj)
        self.done[key], self.sizes[key] = obj, 1  # (met again inside itself: counted once)
        out, parts = self.rebuilt(obj, kind)
        self.done[key] = out
        self.sizes[key] = size = 1 + sum(self.sizes.get(id(p)) or weight(p) for p in parts)
        if size > MAX_NODES:
            raise pickle.UnpicklingError(f"a message of more than {MAX_NODES:,} objects (unfolded)")
        return out

    def rebuilt(self, obj: Any, kind: type) -> tuple[Any, list[Any]]:
        """``obj`` with its parts resolved (a fresh tuple or frozenset, else in place), and its parts as met."""
        if kind is dict:
            parts = [p for item in obj.items() for p in item]
            items = [(self(k), self(v)) for k, v in obj.items()]
            obj.clear()
            obj.update(items)
            return obj, parts
        if kind in (tuple, list, set, frozenset):
            parts = list(obj)
            done = [self(x) for x in parts]
            if kind is list:
                obj[:] = done
            elif kind is set:
                obj.clear()
                obj.update(done)
            return (obj if kind in (list, set) else kind(done)), parts
        if plain_class(kind):  # a record this message built (a fresh object: its fields are set in place)
            fields = record_fields(obj)
            for name, value in fields.items():
                object.__setattr__(obj, name, self(value))
            derive(obj, kind)
            return obj, list(fields.values())
        return obj, []


@functools.lru_cache(maxsize=None)
def _derived(kind: type) -> tuple[dataclasses.Field, ...]:  # type: ignore[type-arg]
    """The fields of a record class that are not given to it (``init=False``), once per class."""
    return tuple(f for f in dataclasses.fields(kind) if not f.init)


def derive(obj: Any, kind: type) -> None:
    """The fields of a record the child built that are not its to give (``init=False``:
    derived from the others, as ``Reads.hosts`` from its devices) computed again by desmon:
    equal records (equality leaves derived fields out) then behave alike in desmon's checks
    and tables. A record its class cannot derive them for is refused."""
    derived = _derived(kind)
    if not derived:
        return
    computed = False
    for f in derived:
        if f.default is not dataclasses.MISSING:
            object.__setattr__(obj, f.name, f.default)
        elif f.default_factory is not dataclasses.MISSING:
            object.__setattr__(obj, f.name, f.default_factory())
        else:
            computed = True  # (its class's __post_init__ computes it)
    if computed:
        try:
            obj.__post_init__()
        except Exception as exc:  # (ModelError, TypeError, ValueError of a record built of odd fields)
            raise pickle.UnpicklingError(f"a {kind.__name__} record whose fields desmon cannot derive the rest from ({type(exc).__name__})") from None


def record_fields(obj: Any) -> dict[str, Any]:
    """The attributes a record the child's message built holds: each of its fields, and (in its
    ``__dict__``) no name its class defines otherwise (one would hide a method of desmon's)."""
    kind = type(obj)
    names = {f.name for f in dataclasses.fields(kind)}
    held = getattr(obj, "__dict__", None)
    if held is None:  # (a record of slots: each of its fields, an AttributeError where one was not set)
        return {name: getattr(obj, name) for name in names}
    odd = [k for k in held if type(k) is not str or (k not in names and hasattr(kind, k))]
    if odd or not names <= held.keys():
        raise pickle.UnpicklingError(f"a {kind.__name__} record whose attributes are not its fields")
    return dict(held)


def registered(cls: type) -> bool:
    from desmon.model.kinds import requirement_classes

    return cls in requirement_classes()


class Handles:
    """The objects desmon handed to the child as handles in this reaction. Their numbers
    grow over the worker's life, so a handle kept from an earlier reaction is refused."""

    def __init__(self) -> None:
        self.base = 0
        self.objects: list[Any] = []
        self.roles: list[str] = []
        self.ids: dict[int, int] = {}

    def give(self, obj: Any, role: str | None = None) -> tuple[int, str]:
        n = self.ids.get(id(obj))
        if n is None or self.objects[n] is not obj:
            n = len(self.objects)
            self.objects.append(obj)
            self.roles.append(role or role_of(obj))
            self.ids[id(obj)] = n
        return self.base + n, self.roles[n]

    def role(self, obj: Any) -> str:
        n = self.ids.get(id(obj))
        return self.roles[n] if n is not None and self.objects[n] is obj else "object"

    def take(self, pid: Any) -> Any:
        if type(pid) is not tuple or len(pid) != 2 or type(pid[0]) is not int or not 0 <= pid[0] - self.base < len(self.objects):
            raise pickle.UnpicklingError("a handle this reaction did not hand out (one kept from an earlier reaction?)")
        return self.objects[pid[0] - self.base]

    def clear(self) -> None:
        self.base += len(self.objects)
        self.objects.clear()
        self.roles.clear()
        self.ids.clear()


def encode(obj: Any, handles: Handles, plain: dict[type, bool]) -> bytes:
    out = io.BytesIO()
    Encoder(out, handles, plain).dump(obj)
    return out.getvalue()


@dataclasses.dataclass(frozen=True)
class Method:
    """Sent back for a method read: the child calls it by name."""

    name: str


@dataclasses.dataclass(frozen=True)
class DefaultChecks:
    """Sent back for a Query port's ``checks`` whose answers are desmon's default checks':
    the child asks its own (a copy of the same code, on copies of the same facts)."""


DEFAULT = DefaultChecks()


@dataclasses.dataclass(frozen=True)
class Blob:
    """Platform states already encoded: the same facts recur from reaction to reaction (the
    checker's store hands out one tuple per facts), so each side encodes and decodes them once."""

    data: bytes


#: the most encoded platform state tuples a worker keeps (each side)
BLOBS = 4096


class Handle:
    """An object desmon hands out by reference, with the role that says what may be read of it."""

    __slots__ = ("obj", "role")

    def __init__(self, obj: Any, role: str | None = None) -> None:
        self.obj, self.role = obj, role


def one_line(text: str) -> str:
    return " ".join(text.split())[:1000]
