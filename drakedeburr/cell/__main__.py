"""``python -m drakedeburr.cell``: regenerate the tool models (drakedeburr/cell/tools.py) and
the arms' pedestals (drakedeburr/cell/mounts.py, from the registry's mounts)."""

import sys

from drakedeburr.cell.mounts import write_pedestals
from drakedeburr.cell.tools import write_tool_models

if __name__ == "__main__":
    for path in write_tool_models(sys.argv[1] if len(sys.argv) > 1 else None):
        print(path)
    if len(sys.argv) == 1:
        for path in write_pedestals():
            print(path)
