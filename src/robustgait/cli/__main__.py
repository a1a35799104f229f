import sys

from robustgait.cli import main

sys.exit(main())
