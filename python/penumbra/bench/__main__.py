"""``python -m penumbra.bench``: the same as ``penumbra bench``."""

import sys

from penumbra.bench import main
from penumbra.errors import PenumbraError

try:
    sys.exit(main())
except PenumbraError as e:
    print(f"penumbra bench: error: {e}", file=sys.stderr)
    sys.exit(2)
