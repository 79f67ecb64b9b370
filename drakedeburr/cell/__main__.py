"""``python -m drakedeburr.cell``: regenerate the tool models from drakedeburr/cell/tools.py."""

import sys

from drakedeburr.cell.tools import write_tool_models

if __name__ == "__main__":
    for path in write_tool_models(sys.argv[1] if len(sys.argv) > 1 else None):
        print(path)
