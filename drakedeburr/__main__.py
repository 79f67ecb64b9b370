import sys

from drakedeburr.cli import main

sys.exit(main())
