"""Grid map (snake model): a polygon layer in, one square cell per region out."""

from qgis.core import (
    QgsFeature,
    QgsFeatureSink,
    QgsField,
    QgsFields,
    QgsPalLayerSettings,
    QgsProcessing,
    QgsProcessingException,
    QgsProcessingLayerPostProcessorInterface,
    QgsProcessingParameterBoolean,
    QgsProcessingParameterDefinition,
    QgsProcessingParameterEnum,
    QgsProcessingParameterFeatureSink,
    QgsProcessingParameterFeatureSource,
    QgsProcessingParameterField,
    QgsProcessingParameterNumber,
    QgsProcessingParameterString,
    QgsVectorLayerSimpleLabeling,
    QgsWkbTypes,
)
from qgis.PyQt.QtCore import QVariant

from .. import binding
from . import common

LOAD_MODELS = ["nodal", "element"]

#: The method's parameters, one row each: (name, label, kind, default, advanced, help). Names
#: are the command line's and the C API's; defaults are the command line's (a test compares them
#: with `snakegrid --help`). The parameter definitions and the help text are both made from this
#: table. Kinds: "double", "int", "bool", "enum" (LOAD_MODELS), "text", "optional double".
METHOD_PARAMETERS = [
    ("alpha", "Beam elasticity α", "double", 1.0, False,
     "Resistance of the network's beams to stretching, > 0."),
    ("beta", "Beam rigidity β", "double", 1.0, False,
     "Resistance of the beams to bending, > 0."),
    ("force_cap", "Force cap T_f (cells)", "double", 0.1, False,
     "Largest force on a centroid, in cells, in (0, 1]."),
    ("max_steps", "Snake steps T_s", "int", 30, False,
     "Most Snake iterations; 0 switches the Snake off."),
    ("refine", "Adjacency-aware refinement", "bool", True, False,
     "Improve the assignment by swapping and moving cells to keep neighbours and directions."),
    ("point_adjacency", "Regions touching at a point are neighbours", "bool", False, False,
     "Queen adjacency instead of rook (a shared border line)."),
    ("seed", "Random seed", "int", 0, False,
     "Seed of every random choice; the same seed gives the same map."),
    ("epsilon", "Convergence threshold ε (cells)", "double", 0.001, True,
     "The Snake stops when no node moves more than this, > 0."),
    ("step_ratio", "Step ratio R", "double", 5.0, True,
     "No node moves more than R times the largest force in one step, >= 1."),
    ("spring", "Weak spring κ", "double", 0.01, True,
     "Fraction of the mean stiffness that anchors the network, > 0."),
    ("stop_on_no_progress", "Stop when the forces stall", "bool", False, True,
     "Stop when the largest force has not fallen for 3 steps."),
    ("load_model", "Load model", "enum", "nodal", True,
     "How forces become loads: nodal (each node's own force) or element (the paper's)."),
    ("vertices_per_region", "Outline vertices per region", "double", 2.0, True,
     "Vertices the simplified map outline keeps per region, > 0."),
    ("simplify_tolerance", "Outline simplification tolerance (cells²)", "optional double", None,
     True, "Visvalingam area tolerance; overrides the vertices per region when given."),
    ("shifts", "Lattice shifts", "text", "0:0,0:0.5,0.5:0,0.5:0.5", True,
     "Lattice origin shifts x:y as fractions of a cell, comma-separated: one candidate each."),
    ("noise_levels", "Noise levels", "text", "0.02,0.04", True,
     "Centroid noise levels of the extra candidates, comma-separated, each in [0, 1]."),
    ("topsis_weights", "Ranking weights", "text", "1,1,1,1", True,
     "Weights of location, adjacency, orientation and shape when ranking the candidates."),
    ("refine_moves", "Refinement moves", "int", 40000, True,
     "Simulated-annealing moves of the refinement."),
    ("refine_temperature", "Refinement temperature", "double", 0.5, True,
     "Starting temperature of the refinement (falls to 0)."),
    ("refine_w_adjacent", "Refinement weight: lost neighbour", "double", 1.0, True,
     "Cost of a neighbour pair whose cells do not touch."),
    ("refine_w_angle", "Refinement weight: direction", "double", 1.0, True,
     "Cost of a pair's direction error, per 90°."),
    ("refine_w_misdirected", "Refinement weight: misdirected pair", "double", 0.5, True,
     "Cost of a pair off by more than 45°."),
    ("refine_w_location", "Refinement weight: distance", "double", 0.25, True,
     "Cost of a region's squared distance to its cell, per cell²."),
    ("refine_cell_ratio", "Free cells offered", "double", 1.3, True,
     "Cells the refinement may use, as a multiple of the number of regions, >= 1."),
    ("refine_swap_only_below", "Swap only below", "int", 20, True,
     "With fewer regions than this the refinement only swaps cells (keeps the outline)."),
    ("threads", "Worker threads", "int", 0, True,
     "Threads the candidates are computed on; 0: as many as the machine has. The result is "
     "the same for every value."),
]

INPUT, ID_FIELD, LABEL_FIELD, OUTPUT, OUTLINE = (
    "INPUT", "ID_FIELD", "LABEL_FIELD", "OUTPUT", "OUTLINE")


def _definition(name, label, kind, default, advanced, help_text):
    if kind in ("double", "optional double"):
        parameter = QgsProcessingParameterNumber(
            name, label, QgsProcessingParameterNumber.Double, default,
            optional=kind == "optional double", minValue=0.0)
    elif kind == "int":
        parameter = QgsProcessingParameterNumber(
            name, label, QgsProcessingParameterNumber.Integer, default, minValue=0)
    elif kind == "bool":
        parameter = QgsProcessingParameterBoolean(name, label, default)
    elif kind == "enum":
        parameter = QgsProcessingParameterEnum(
            name, label, LOAD_MODELS, defaultValue=LOAD_MODELS.index(default))
    else:
        parameter = QgsProcessingParameterString(name, label, default)
    if advanced:
        parameter.setFlags(parameter.flags() | QgsProcessingParameterDefinition.FlagAdvanced)
    parameter.setHelp(help_text)
    return parameter


def _help():
    def shown(kind, default):
        if default is None:
            return "none"
        if kind == "bool":
            return "yes" if default else "no"
        return str(default)

    rows = "".join(
        f"<li><b>{label}</b> ({name}, default {shown(kind, default)}): {text}</li>"
        for name, label, kind, default, advanced, text in METHOD_PARAMETERS if not advanced)
    advanced = "".join(
        f"<li><b>{label}</b> ({name}, default {shown(kind, default)}): {text}</li>"
        for name, label, kind, default, adv, text in METHOD_PARAMETERS if adv)
    added = "".join(f"<li><b>{name}</b>: {meaning}</li>" for name, _, meaning in common.GRID_FIELDS)
    metrics = "".join(f"<li>{label}</li>" for _, label, _ in common.LAYOUT_OUTPUTS)
    return (
        "<p>Makes a grid map (tile map): one equal square cell per region, placed so that cells "
        "stay near their regions, neighbours stay neighbours, directions hold and the whole "
        "keeps the map's outline.</p>"
        "<p>The method (the snake model of Wei, Yang, Xu and Ding, 2024): the region centroids "
        "and the map outline form a network of elastic beams; forces pull the centroids towards "
        "an even spacing of one cell while the beams keep the network's shape (the Snake). A "
        "square lattice is then fitted to the moved outline and every region gets a cell by an "
        "optimal assignment, which an adjacency-aware refinement then improves; several "
        "candidates (lattice shifts, noisy starts) are made this way and ranked by their "
        "metrics.</p>"
        "<p><b>Input layer</b>: polygons, any source QGIS reads (tick <i>Selected features "
        "only</i> to use a selection). A geographic CRS is projected to Lambert azimuthal "
        "equal-area centred on the layer; the output is in the working CRS.</p>"
        "<p><b>Id field</b>: unique region id (default: the feature id). <b>Label field</b>: a "
        "short name (e.g. an abbreviation) used to label the cells when the output is loaded "
        "(default: abbr, else name, if present).</p>"
        f"<p>Method parameters (lengths in cells):</p><ul>{rows}</ul>"
        f"<p>Advanced parameters:</p><ul>{advanced}</ul>"
        "<p><b>Grid map</b>: one square per region with every source field and "
        f"</p><ul>{added}</ul>"
        "<p><b>Moved outline</b> (optional): the map outline after the Snake, which the lattice "
        "was fitted to.</p>"
        f"<p>Numeric outputs, the layout metrics:</p><ul>{metrics}</ul>"
    )


def option_text(kind, value):
    """A parameter value as the C API's option text."""
    if kind == "bool":
        return "true" if value else "false"
    if kind == "enum":
        return LOAD_MODELS[value]
    if kind == "int":
        return str(int(value))
    if kind in ("double", "optional double"):
        return repr(float(value))
    return str(value).strip()


class LabelCells(QgsProcessingLayerPostProcessorInterface):
    """Labels the cells of the loaded grid layer with the short label field."""

    # QGIS does not own post-processors made in Python: keep the live one referenced.
    current = None

    def __init__(self, field):
        super().__init__()
        self.field = field

    def postProcessLayer(self, layer, context, feedback):  # noqa: N802 (QGIS's name)
        settings = QgsPalLayerSettings()
        settings.fieldName = self.field
        settings.placement = QgsPalLayerSettings.OverPoint
        layer.setLabeling(QgsVectorLayerSimpleLabeling(settings))
        layer.setLabelsEnabled(True)
        layer.triggerRepaint()

    @classmethod
    def create(cls, field):
        cls.current = cls(field)
        return cls.current


class GridMapAlgorithm(common.SnakegridAlgorithm):
    def name(self):
        return "gridmap"

    def displayName(self):  # noqa: N802 (QGIS's names throughout)
        return "Grid map (snake model)"

    def shortHelpString(self):  # noqa: N802
        return _help()

    def createInstance(self):  # noqa: N802
        return GridMapAlgorithm()

    def initAlgorithm(self, config=None):  # noqa: N802
        self.addParameter(QgsProcessingParameterFeatureSource(
            INPUT, "Input polygon layer", [QgsProcessing.TypeVectorPolygon]))
        self.addParameter(QgsProcessingParameterField(
            ID_FIELD, "Id field (unique; default: the feature id)", parentLayerParameterName=INPUT,
            optional=True))
        self.addParameter(QgsProcessingParameterField(
            LABEL_FIELD, "Short label field (default: abbr, else name)",
            parentLayerParameterName=INPUT, optional=True))
        for row in METHOD_PARAMETERS:
            self.addParameter(_definition(*row))
        self.addParameter(QgsProcessingParameterFeatureSink(
            OUTPUT, "Grid map", QgsProcessing.TypeVectorPolygon))
        self.addParameter(QgsProcessingParameterFeatureSink(
            OUTLINE, "Moved outline", QgsProcessing.TypeVectorPolygon, optional=True,
            createByDefault=False))
        common.add_layout_outputs(self)

    def options(self, parameters, context):
        options = {}
        for name, _, kind, _, _, _ in METHOD_PARAMETERS:
            if kind == "optional double" and parameters.get(name) in (None, ""):
                continue  # unset: the library's default ("none")
            if kind in ("double", "optional double"):
                value = self.parameterAsDouble(parameters, name, context)
            elif kind == "int":
                value = self.parameterAsInt(parameters, name, context)
            elif kind == "bool":
                value = self.parameterAsBoolean(parameters, name, context)
            elif kind == "enum":
                value = self.parameterAsEnum(parameters, name, context)
            else:
                value = self.parameterAsString(parameters, name, context)
            options[name] = option_text(kind, value)
        return options

    def processAlgorithm(self, parameters, context, feedback):  # noqa: N802
        library = common.library()
        source = self.parameterAsSource(parameters, INPUT, context)
        if source is None:
            raise QgsProcessingException(self.invalidSourceError(parameters, INPUT))
        id_field = self.parameterAsString(parameters, ID_FIELD, context)
        label_field = self.parameterAsString(parameters, LABEL_FIELD, context)
        options = self.options(parameters, context)

        regions = common.Regions(source, id_field, "The input layer", feedback)
        crs = common.working_crs(regions.crs, regions.extent(), feedback)
        try:
            grid = library.generate(
                regions.wkb(crs, context), options, common.Progress(feedback, 10.0, 95.0))
        except binding.SnakegridError as e:
            raise common.library_failure(e) from e

        fields, kept = common.grid_fields(regions.fields)
        sink, dest_id = self.parameterAsSink(
            parameters, OUTPUT, context, fields, QgsWkbTypes.Polygon, crs)
        if sink is None:
            raise QgsProcessingException(self.invalidSinkError(parameters, OUTPUT))
        for feature, cell in zip(regions.features, grid.cells):
            attributes = feature.attributes()
            out = QgsFeature(fields)
            out.setAttributes([attributes[i] for i in kept] + [
                cell.col, cell.row, cell.metrics.displacement, cell.metrics.neighbours_kept,
                cell.metrics.orientation_error])
            out.setGeometry(common.geometry_from_wkb(cell.wkb))
            if not sink.addFeature(out, QgsFeatureSink.FastInsert):
                raise QgsProcessingException(self.writeFeatureError(sink, parameters, OUTPUT))
        results = {OUTPUT: dest_id}

        outline_fields = QgsFields()
        outline_fields.append(QgsField("regions", QVariant.Int))
        outline_sink, outline_id = self.parameterAsSink(
            parameters, OUTLINE, context, outline_fields, QgsWkbTypes.MultiPolygon, crs)
        if outline_sink is not None:
            outline = QgsFeature(outline_fields)
            outline.setAttributes([len(grid.cells)])
            outline.setGeometry(common.geometry_from_wkb(grid.moved_outline_wkb))
            if not outline_sink.addFeature(outline, QgsFeatureSink.FastInsert):
                raise QgsProcessingException(
                    self.writeFeatureError(outline_sink, parameters, OUTLINE))
            results[OUTLINE] = outline_id

        label = label_field or next(
            (name for name in ("abbr", "name") if regions.fields.lookupField(name) >= 0), "")
        if label and context.willLoadLayerOnCompletion(dest_id):
            context.layerToLoadOnCompletionDetails(dest_id).setPostProcessor(
                LabelCells.create(label))
        feedback.setProgress(100.0)
        feedback.pushInfo(f"{len(grid.cells)} cells of {grid.cell_size:.6g} map units.")
        results.update(common.layout_results(grid.metrics, feedback))
        return results
