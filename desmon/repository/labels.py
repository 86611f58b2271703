"""Node and edge labels of the repository graph (docs/design.md §3), used everywhere."""

from typing import Final

# nodes
PLATFORM: Final = "Platform"
DEVICE: Final = "Device"
PERCEPTION_GRAPH: Final = "PerceptionGraph"
DEPLOYMENT: Final = "Deployment"
REQUIREMENT: Final = "Requirement"
CONTEXT: Final = "Context"
ROBOT: Final = "Robot"

# edges
HAS_DEVICE: Final = "HAS_DEVICE"
RESOLVES: Final = "RESOLVES"
REQUIRES: Final = "REQUIRES"
EXECUTABLE_ON: Final = "EXECUTABLE_ON"
DEPLOYED_ON: Final = "DEPLOYED_ON"
DEPLOYMENT_HISTORY: Final = "DEPLOYMENT_HISTORY"
IN_CONTEXT: Final = "IN_CONTEXT"

NODE_LABELS: Final = (PLATFORM, DEVICE, PERCEPTION_GRAPH, DEPLOYMENT, REQUIREMENT, CONTEXT, ROBOT)
EDGE_LABELS: Final = (HAS_DEVICE, RESOLVES, REQUIRES, EXECUTABLE_ON, DEPLOYED_ON, DEPLOYMENT_HISTORY, IN_CONTEXT)
#: The edges that describe deployments (what Fig. 5a-d shows changing).
DEPLOYMENT_EDGES: Final = (HAS_DEVICE, EXECUTABLE_ON, DEPLOYED_ON, DEPLOYMENT_HISTORY)
