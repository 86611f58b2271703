"""L2: the graph repository (Insert / Query / Notify) on networkx, with change log and exports."""

from desmon.repository import labels
from desmon.repository.facts import (
    ImmediateControl,
    RepositoryInsert,
    load_model,
    record_start,
    record_stop,
    set_context,
    set_device_working,
    set_load,
    set_platform_up,
)
from desmon.repository.query import RepositoryQuery
from desmon.repository.store import Change, Repository, Subscription, graph_to_graphml, graph_to_json, node_id

__all__ = [
    "labels", "ImmediateControl", "RepositoryInsert", "load_model", "record_start", "record_stop", "set_context",
    "set_device_working", "set_load", "set_platform_up", "RepositoryQuery", "Change", "Repository",
    "Subscription", "graph_to_graphml", "graph_to_json", "node_id",
]
