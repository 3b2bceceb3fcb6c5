# Type stub: at run time toolkit.structures is toolkit.papers.structures itself (a short name
# registered by toolkit/__init__.py); this stub gives type checkers the same names.
from .papers.structures import *  # noqa: F403
