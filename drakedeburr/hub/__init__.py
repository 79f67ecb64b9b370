"""drakedeburr.hub stage: parametric hub models, ground-truth window edges, simulated scans."""

from drakedeburr.hub.catalogue import BUNDLED, DEFAULT_HUB, bundled_spec
from drakedeburr.hub.generate import GeneratedHub, generate_hub
from drakedeburr.hub.model import HubModel, load_hub
from drakedeburr.hub.scan import simulate_scan
from drakedeburr.hub.spec import HubSpec, load_spec, spec_to_yaml
from drakedeburr.hub.types import ScanCloud, WindowEdge, WindowKind

__all__ = [
    "BUNDLED", "DEFAULT_HUB", "bundled_spec", "GeneratedHub", "generate_hub", "HubModel",
    "load_hub", "simulate_scan", "HubSpec", "load_spec", "spec_to_yaml", "ScanCloud",
    "WindowEdge", "WindowKind",
]
