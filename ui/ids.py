"""The ids of the workbench's components, one definition each: the pages lay them out and their
callbacks listen to them by these names (as in the Dash multi-page demos' ``ids.py``).

The values are part of the workbench's outside: the browser tests find the components by them and
the clientside callbacks read some of them, so a value changes only with those. A computation's
controls, stores and downloads are named after one prefix (:class:`Group`: ``bif`` -> ``bif-run``,
``bif-csv``, ...); everything else is a constant. Pattern-matching ids are dicts with a ``type``
(``*_TYPE`` below) and a key of their own.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any


@dataclass(frozen=True)
class Group:
    """The ids one prefix names: a long computation's controls and stores (:mod:`ui.jobs`), its
    refusal line, its downloads (:func:`ui.components.downloads`), and the line that says which
    designs a comparison shows (:func:`ui.compare.register_selection`)."""

    prefix: str
    requests_id: str = ""  # the store of the shown results' requests, if not PREFIX-requests

    def _id(self, name: str) -> str:
        return f"{self.prefix}-{name}"

    @property
    def run(self) -> str:
        return self._id("run")

    @property
    def cancel(self) -> str:
        return self._id("cancel")

    @property
    def progress(self) -> str:
        return self._id("progress")

    @property
    def status(self) -> str:
        return self._id("status")

    @property
    def poll(self) -> str:
        return self._id("poll")

    @property
    def requests(self) -> str:
        return self.requests_id or self._id("requests")

    @property
    def go(self) -> str:
        return self._id("go")

    @property
    def ready(self) -> str:
        return self._id("ready")

    @property
    def sketched(self) -> str:
        return self._id("sketched")

    @property
    def landed(self) -> str:
        return self._id("landed")

    @property
    def drawn(self) -> str:
        return self._id("drawn")

    @property
    def error(self) -> str:
        return self._id("error")

    @property
    def stale(self) -> str:
        return self._id("stale")

    @property
    def designs(self) -> str:
        return self._id("designs")

    @property
    def csv(self) -> str:
        return self._id("csv")

    @property
    def json(self) -> str:
        return self._id("json")

    @property
    def download(self) -> str:
        return self._id("download")


# -- the shell and the design panel (every page) -----------------------------------------------------------

#: dash.page_container's Location: Dash Pages' router replaces the page when its path or query changes.
PAGES_LOCATION = "_pages_location"
URL_UPDATE = "url-update"  # a page's partial updates of the address
# the design panel's (a store of its own: two writers' updates of one store in one render keep only the last)
URL_DESIGN_UPDATE = "url-design-update"
URL_SINK = "url-sink"  # the address as the updater left it
DESIGN_TOGGLE = "design-toggle"
DESIGN_PANEL = "design-panel"
DESIGN_ERROR = "design-error"
MATERIAL = "material"
RESET_DESIGN = "reset-design"
ADVANCED = "advanced"
#: The advanced parameters' boxes: filled when their section is first opened (fewer components on a slider step).
ADVANCED_GRID = "advanced-grid"
ADVANCED_SUMMARY = "advanced-summary"
PARAM_TYPE = "param"  # {"type", "name"}: a parameter's slider or number box
PARAM_BOX_TYPE = "param-box"  # the number box beside a slider
PARAM_ERROR_TYPE = "param-error"
DESIGN_STORE_TYPE = "design"  # {"type", "page"}: a page's design store


def param(name: Any) -> dict[str, Any]:
    """A parameter's slider or number box (``name``: the parameter, or ALL)."""
    return {"type": PARAM_TYPE, "name": name}


def param_box(name: Any) -> dict[str, Any]:
    return {"type": PARAM_BOX_TYPE, "name": name}


def param_error(name: Any) -> dict[str, Any]:
    return {"type": PARAM_ERROR_TYPE, "name": name}


def design_store(page: Any) -> dict[str, Any]:
    """A page's design store. Each page has its own so that its callbacks' inputs all live on that
    page (a callback with an input missing from the layout is an error in the browser)."""
    return {"type": DESIGN_STORE_TYPE, "page": page}


# -- saved designs (the panel's block, ui.sessions) --------------------------------------------------------

DESIGNS_FOLLOW = "designs-follow-design"  # the page's design while designs are saved (the saved list marks it)
SAVED = "designs-saved"  # the localStorage store of the saved designs (shared by every page and tab)
DESIGNS = "designs"
DESIGN_ASK = "design-ask"
DESIGN_UPLOAD_ASK = "design-upload-ask"
DESIGN_OPEN = "design-open"
DESIGN_OPEN_SINK = "design-open-sink"
DESIGN_NAME = "design-name"
DESIGN_SAVE = "design-save"
DESIGNS_MESSAGE = "designs-message"
DESIGNS_LIST = "designs-list"
DESIGN_COMPARE = "design-compare"
DESIGN_DOWNLOAD_JSON = "design-download-json"
DESIGN_UPLOAD = "design-upload"
DESIGN_DOWNLOAD = "design-download"
DESIGN_LINK = "design-link"
SAVED_NAME_TYPE = "saved-name"  # {"type", "id"}: a saved design's name box, Open and Delete buttons
SAVED_OPEN_TYPE = "saved-open"
SAVED_DELETE_TYPE = "saved-delete"


def saved(kind: str, entry_id: Any) -> dict[str, Any]:
    return {"type": kind, "id": entry_id}


# -- Overview (/) ------------------------------------------------------------------------------------------

OV = "ov"  # the page's design store
OV_GROUP = Group("ov")  # the Hopf table's error line and downloads
OV_FZ = "ov-fz"
OV_VMAX = "ov-vmax"
OV_GROWTH = "ov-growth"
OV_TABLE = "ov-table"
OV_HOPF_TABLE = "ov-hopf-table"
OV_DATA = "ov-data"
OV_CMP = Group("ov-cmp")
OV_CMP_GRAPH = "ov-cmp-graph"
OV_CMP_TABLE = "ov-cmp-table"
OV_CMP_SUMMARY = "ov-cmp-summary"
OV_BOUNDARY = Group("ov-boundary", "ovb-requests")
OV_BOUNDARY_FILES = Group("ovb")
OV_BOUNDARY_GRAPH = "ov-boundary-graph"
OV_REGIONS = Group("ov-regions", "ovr-requests")
OV_REGIONS_FILES = Group("ovr")
OV_REGIONS_GRAPH = "ov-regions-graph"

# -- Devices (/devices) ------------------------------------------------------------------------------------

DEV = "dev"
DEV_GROUP = Group("dev")
DEV_METRICS = "dev-metrics"
DEV_TORQUE = "dev-torque"
DEV_STIFFNESS = "dev-stiffness"
DEV_PD = "dev-pd"

# -- Time history (/time-history) --------------------------------------------------------------------------

TH = "th"
TH_GROUP = Group("th", "th-request")
TH_CONFIG = "th-config"
TH_V = "th-v"
TH_FZ = "th-fz"
TH_TEND = "th-tend"
TH_START = "th-start"
TH_PSI0 = "th-psi0"
TH_LAT0 = "th-lat0"
TH_OP_TYPE = "th-op"  # {"type", "name"}: an operating point's button
TH_SETTLED = "th-settled"
TH_METRICS = "th-metrics"
TH_SERIES = "th-series"
TH_SPECTRUM = "th-spectrum"
TH_PHASE = "th-phase"
TH_AUTORUN = "th-autorun"
TH_KICK = "th-kick"  # a run asked from the margins' table (its start already in the boxes)
TH_BISTABLE = "th-bistable"
TH_EXACT = "th-exact"  # the NES torque choice
TH_WINDOW = "th-window"  # the time window the series figure was zoomed or panned to
TH_STARTS = "th-starts"  # which attractor each start ended on (a Bistable map point)  # the note that the map shades the point Bistable
THM = Group("thm")  # the point's disturbance margins
THM_TABLE = "thm-table"
THM_SUMMARY = "thm-summary"
THM_RUN_TYPE = "thm-run"  # {"type", "index"}: the run button of an attractor's row
THM_DIRECTION = "thm-direction"  # the kick's direction: a component, a mix or all (energy)
THM_MIX = "thm-mix"  # the mix's components, "psi=0.01,dpsi=0.2"
THM_ORIGIN = "thm-origin"  # what the kick is added to: straight rolling, or the standard start's attractor


def th_op(name: Any) -> dict[str, Any]:
    return {"type": TH_OP_TYPE, "name": name}


def thm_run(index: Any) -> dict[str, Any]:
    """The button that runs the time history from the smallest kick to attractor ``index`` (or ALL)."""
    return {"type": THM_RUN_TYPE, "index": index}


# -- Bifurcation (/bifurcation) ----------------------------------------------------------------------------

BIF = "bif"
BIF_GROUP = Group("bif")
BIF_FZ = "bif-fz"
BIF_VMIN = "bif-vmin"
BIF_VMAX = "bif-vmax"
BIF_CONFIGS = "bif-configs"
BIF_EXACT = "bif-exact"
BIF_GRAPH = "bif-graph"
BIF_TABLE = "bif-table"
BIF_SUMMARY = "bif-summary"
BIFC = Group("bifc")  # the comparison of saved designs
BIFC_CONFIG = "bifc-config"
BIFC_GRAPH = "bifc-graph"
BIFC_TABLE = "bifc-table"
BIFC_SUMMARY = "bifc-summary"

# -- Stability map (/stability-map) ------------------------------------------------------------------------

MAP = "map"
MAP_GROUP = Group("map")
MAP_SHADE = "map-shade"
MAP_OVERLAY = "map-overlay"
MAP_FZMIN = "map-fzmin"
MAP_FZMAX = "map-fzmax"
MAP_VMIN = "map-vmin"
MAP_VMAX = "map-vmax"
MAP_RES = "map-res"
MAP_GRAPH = "map-graph"
MAP_HINT = "map-hint"
MAP_TABLE = "map-table"
MAP_SUMMARY = "map-summary"
MAP_NAV = "map-nav"
MAPC = Group("mapc")
MAPC_CONFIG = "mapc-config"
MAPC_FZ = "mapc-fz"
MAPC_GRAPH = "mapc-graph"
MAPC_TABLE = "mapc-table"
MAPC_SUMMARY = "mapc-summary"
MAPM = Group("mapm")  # the disturbance margins on the map
MAPM_NV = "mapm-nv"
MAPM_NFZ = "mapm-nfz"
MAPM_MAX = "mapm-max"
MAPM_GRAPH = "mapm-graph"
MAPM_HINT = "mapm-hint"
MAPM_TABLE = "mapm-table"
MAPM_SUMMARY = "mapm-summary"
MAPM_NAV = "mapm-nav"

# -- Ground run (/ground-run) ------------------------------------------------------------------------------

GR = "gr"
GR_GROUP = Group("gr")
GR_PRESET = "gr-preset"
GR_CONFIG = "gr-config"
GR_PSI_THR = "gr-psi-thr"
GR_LAT_THR = "gr-lat-thr"
GR_EXACT = "gr-exact"
GR_SETTINGS = "gr-settings"
GR_SETTINGS_ERROR = "gr-settings-error"
GR_TABLE_ERROR = "gr-table-error"
GR_ASSUMPTIONS = "gr-assumptions"
GR_TABLE = "gr-table"
GR_ADD_ROW = "gr-add-row"
GR_RESET = "gr-reset"
GR_SOURCE = "gr-source"
GR_ADDRESS = "gr-address"
GR_SUMMARY = "gr-summary"
GR_SUMMARY_TABLE = "gr-summary-table"
GR_PLANE = "gr-plane"
GR_TIME = "gr-time"
GR_SPEED = "gr-speed"
GR_PRESET_ROWS = "gr-preset-rows"
GR_KICK = "gr-kick"  # the kick's kind (none, psi, dpsi)
GR_KICK_SIZE = "gr-kick-size"
GR_KICK_AT = "gr-kick-at"  # at a time or at a speed
GR_KICK_WHEN = "gr-kick-when"  # that time (s) or speed (m/s)
GR_KICK_NOTE = "gr-kick-note"  # what the chosen scenario is

# -- Parametric study (/study) -----------------------------------------------------------------------------

STUDY = "study"
STUDY_GROUP = Group("study", "study-request")
STUDY_PARAM = "study-param"
STUDY_VALUES = "study-values"
STUDY_FZ = "study-fz"
STUDY_CONFIGS = "study-configs"
STUDY_RANGE = "study-range"
STUDY_SKIPPED = "study-skipped"
STUDY_LOG = "study-log"
STUDY_VIEW = "study-view"
STUDY_GRAPH = "study-graph"
STUDY_TABLE = "study-table"
STUDY_SUMMARY = "study-summary"
STUDY_PIVOT = "study-pivot"

# -- Design decisions (/design) ----------------------------------------------------------------------------

DES = "des"
DES_CONFIG = "des-config"
DES_CONFIG_ERROR = "des-config-error"
DES_FZ = "des-fz"
DES_FZ_ERROR = "des-fz-error"
SENSITIVITIES = "sensitivities"  # the sections' headings (the page's anchors)
OPTIMISER = "optimiser"
ROBUSTNESS = "robustness"
SENS = Group("sens")
SENS_BY = "sens-by"
SENS_SHOW = "sens-show"
SENS_SUMMARY = "sens-summary"
SENS_CHARTS = "sens-charts"
SENS_DATA = "sens-data"
OPT = Group("opt")
OPT_OBJECTIVE = "opt-objective"
OPT_SEARCH = "opt-search"
OPT_SEARCH_ERROR = "opt-search-error"
OPT_CONSTRAINTS = "opt-constraints"
OPT_CONSTRAINTS_ERROR = "opt-constraints-error"
OPT_ADD = "opt-add"
OPT_STARTS = "opt-starts"
OPT_STARTS_ERROR = "opt-starts-error"
OPT_RUNS = "opt-runs"
OPT_RUNS_ERROR = "opt-runs-error"
OPT_SEED = "opt-seed"
OPT_SEED_ERROR = "opt-seed-error"
OPT_SUMMARY = "opt-summary"
OPT_RESULT_LINE = "opt-result-line"
OPT_LINK = "opt-link"
OPT_DESIGN = "opt-design"
OPT_DESIGN_TABLE = "opt-design-table"
OPT_FIGURES = "opt-figures"
OPT_FIGURES_TABLE = "opt-figures-table"
OPT_HISTORY = "opt-history"
ROB = Group("rob")
ROB_TOLERANCES = "rob-tolerances"
ROB_TOLERANCES_ERROR = "rob-tolerances-error"
ROB_ADD = "rob-add"
ROB_SAMPLES = "rob-samples"
ROB_SAMPLES_ERROR = "rob-samples-error"
ROB_SEED = "rob-seed"
ROB_SEED_ERROR = "rob-seed-error"
ROB_WARNINGS = "rob-warnings"
ROB_HISTOGRAMS = "rob-histograms"
ROB_TABLE = "rob-table"
ROB_STATS = "rob-stats"
ROB_SHIMMY = "rob-shimmy"


def sens_chart(quantity: str) -> str:
    """The tornado chart of a sensitivity quantity (its key: hopf_V1, min_shimmy_Fz, ...)."""
    return f"sens-{quantity}"


def rob_histogram(quantity: str) -> str:
    """The histogram of a sampled quantity (V1, V2, Fzmin)."""
    return f"rob-hist-{quantity}"


# -- Validation (/validation) and API (/api) ---------------------------------------------------------------

VAL = "val"
VAL_GROUP = Group("val")
VAL_CONTENT = "val-content"
VAL_RUN = "val-run"
VAL_DATA = "val-data"
VAL_HOPF = "val-hopf"
VAL_AMPLITUDE = "val-amplitude"
VAL_SANITY = "val-sanity"
VAL_DISAGREEMENT = "val-disagreement"
API = "api"
API_ENDPOINTS = "api-endpoints"
