"""``python -m drakedeburr.robots``: regenerate the KUKA and FANUC arm models."""

import sys

from drakedeburr.robots.arm_models import write_arm_models

if __name__ == "__main__":
    for path in write_arm_models(sys.argv[1] if len(sys.argv) > 1 else None):
        print(path)
