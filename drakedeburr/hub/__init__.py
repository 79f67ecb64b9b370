"""drakedeburr.hub stage: parametric hub models, ground-truth window edges, simulated scans."""

from drakedeburr._lazy import lazy_exports

__all__, __getattr__, __dir__ = lazy_exports(__name__, {
    "catalogue": ("BUNDLED", "DEFAULT_HUB", "bundled_spec"),
    "generate": ("GeneratedHub", "generate_hub"),
    "model": ("HubModel", "load_hub"),
    "scan": ("ScannerModel", "simulate_scan"),
    "spec": ("HubSpec", "load_spec", "spec_to_yaml"),
    "types": ("ScanCloud", "WindowEdge", "WindowKind"),
})
