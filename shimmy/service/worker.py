"""``python -m shimmy.service.worker JOB_ID``: run one background job (started by jobs.submit)."""

import sys

from .jobs import run

if __name__ == "__main__":
    run(sys.argv[1])
