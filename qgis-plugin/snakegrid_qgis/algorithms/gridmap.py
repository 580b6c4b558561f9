"""Grid map (snake model): a polygon layer in, one square or hexagonal cell per region out."""

from qgis.core import (
    QgsFeature,
    QgsFeatureSink,
    QgsField,
    QgsFields,
    QgsPalLayerSettings,
    QgsProcessing,
    QgsProcessingException,
    QgsProcessingLayerPostProcessorInterface,
    QgsProcessingOutputNumber,
    QgsProcessingParameterCrs,
    QgsProcessingParameterFeatureSink,
    QgsProcessingParameterFeatureSource,
    QgsProcessingParameterField,
    QgsProcessingParameterFileDestination,
    QgsVectorLayerSimpleLabeling,
    QgsWkbTypes,
)
from qgis.PyQt.QtCore import QVariant

from .. import library
from . import common, parameters

INPUT, ID_FIELD, GROUP_FIELD, LABEL_FIELD, TARGET_CRS, OUTPUT, OUTLINE, HEXJSON = (
    "INPUT", "ID_FIELD", "GROUP_FIELD", "LABEL_FIELD", "TARGET_CRS", "OUTPUT", "OUTLINE",
    "HEXJSON")
PIN_COL_FIELD, PIN_ROW_FIELD = "PIN_COL_FIELD", "PIN_ROW_FIELD"

#: The group metrics (method.md section 10), numeric outputs of a run with a group field.
GROUP_OUTPUTS = [
    ("GROUPS_WHOLE", "Groups: share of blocks in one piece (higher is better)", "whole"),
    ("GROUP_ADJACENCY", "Groups: share of neighbouring groups kept within reach (higher is "
     "better)", "adjacency"),
    ("GROUP_ORIENTATION", "Groups: mean direction error between groups, degrees (lower is "
     "better)", "orientation"),
    ("GROUP_CONTACTS", "Groups: touching cells of different groups (0 with a gap)", "contacts"),
]

ABOUT = """\
Makes a grid map (tile map): one equal cell per region (squares, or hexagons with cell = hex), placed so that cells stay near \
their regions, neighbours stay neighbours, directions hold and the whole keeps the map's outline.
The method (the snake model of Wei, Yang, Xu and Ding, 2024): the region centroids and the map \
outline form a network of elastic beams; forces pull the centroids towards an even spacing of \
one cell while the beams keep the network's shape (the Snake). A square lattice is then fitted \
to the moved outline and every region gets a cell by an optimal assignment, which an \
adjacency-aware refinement improves; several candidates (lattice shifts, noisy starts) are made \
this way and ranked by their metrics.
INPUT: polygons, any source QGIS reads (tick Selected features only to use a selection).
ID_FIELD: unique region id (default: the feature id). GROUP_FIELD (optional): the regions of \
each group keep together, one block of cells per group on each landmass, the blocks placed like \
the groups (a NULL or blank value is a group of its own; the parameter group_gap 1 keeps blocks of \
different groups a cell apart); grid_group numbers the blocks. PIN_COL_FIELD and PIN_ROW_FIELD \
(optional, both or neither): each pinned region's cell, whole numbers as grid_col and grid_row \
count them (NULL: free); the pinned regions keep their cells and every cell is numbered in their \
frame. LABEL_FIELD: a short name used to label \
the cells when the output is loaded (default: abbr, else name, if present).
TARGET_CRS: the working and output CRS, as the command line's -t_srs (default: the layer's CRS \
when it is projected, else an equal-area CRS centred on the layer, chosen by the library).
OUTPUT: one cell per region with every source field and {fields}.
OUTLINE (optional): the map outline after the Snake, which the lattice was fitted to.
HEXJSON (optional, hexagonal cells only): the layout as a HexJSON file (Open Innovations' \
format, as d3-hexjson draws it), each hexagon keyed and labelled by its region id.
Numeric outputs, the layout metrics: {metrics}.
Method parameters (lengths in cells):
{parameters}"""


def _options():
    """The library's parameter table, or [] while the package is missing (the algorithm then
    only says how to install it)."""
    if library.problem():
        return []
    import snakegrid

    return snakegrid.options()


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
    def __init__(self):
        super().__init__()
        self.options = _options()

    def name(self):
        return "gridmap"

    def displayName(self):  # noqa: N802 (QGIS's names throughout)
        return "Grid map (snake model)"

    def shortHelpString(self):  # noqa: N802
        problem = library.problem()
        if problem:
            return problem
        import snakegrid

        return ABOUT.format(
            fields=", ".join(f"{f.name} ({f.description})" for f in snakegrid.fields()),
            metrics=", ".join(label for _, label, _ in common.LAYOUT_OUTPUTS),
            parameters=parameters.help_text(self.options))

    def createInstance(self):  # noqa: N802
        return GridMapAlgorithm()

    def initAlgorithm(self, config=None):  # noqa: N802
        self.addParameter(QgsProcessingParameterFeatureSource(
            INPUT, "Input polygon layer", [QgsProcessing.TypeVectorPolygon]))
        self.addParameter(QgsProcessingParameterField(
            ID_FIELD, "Id field (unique; default: the feature id)", parentLayerParameterName=INPUT,
            optional=True))
        self.addParameter(QgsProcessingParameterField(
            GROUP_FIELD, "Group field (regions kept together; optional)",
            parentLayerParameterName=INPUT, optional=True))
        self.addParameter(QgsProcessingParameterField(
            LABEL_FIELD, "Short label field (default: abbr, else name)",
            parentLayerParameterName=INPUT, optional=True))
        self.add_placement_parameters()
        for option in self.options:
            self.addParameter(parameters.definition(option))
        self.addParameter(QgsProcessingParameterFeatureSink(
            OUTPUT, "Grid map", QgsProcessing.TypeVectorPolygon))
        self.addParameter(QgsProcessingParameterFeatureSink(
            OUTLINE, "Moved outline", QgsProcessing.TypeVectorPolygon, optional=True,
            createByDefault=False))
        self.addParameter(QgsProcessingParameterFileDestination(
            HEXJSON, "HexJSON file (hexagonal cells only)", "HexJSON (*.hexjson *.json)",
            optional=True, createByDefault=False))
        common.add_layout_outputs(self)
        for name, label, _ in GROUP_OUTPUTS:
            self.addOutput(QgsProcessingOutputNumber(name, label))

    def add_placement_parameters(self):
        """The parameters that say where the cells go: the working CRS and the pins."""
        self.addParameter(QgsProcessingParameterCrs(
            TARGET_CRS, "Working and output CRS (default: the layer's if projected, else an "
            "equal-area CRS centred on it)", optional=True))
        for name, label in ((PIN_COL_FIELD, "Pin column field (pinned cells; optional)"),
                            (PIN_ROW_FIELD, "Pin row field, from the top (with the column)")):
            self.addParameter(QgsProcessingParameterField(
                name, label, parentLayerParameterName=INPUT, optional=True,
                type=QgsProcessingParameterField.Numeric))

    def placement(self, sg, features, parameters_, context, feedback):
        """The working CRS, the cut that readies a region for it (None: none needed) and the
        regions' pins (None: no pins)."""
        target = self.parameterAsCrs(parameters_, TARGET_CRS, context)
        crs, cut = common.working_crs(sg, features, target, feedback)
        return crs, cut, features.pins

    def checkParameterValues(self, parameters_, context):  # noqa: N802
        # The library refuses a bad value by name before any feature is read.
        ok, message = super().checkParameterValues(parameters_, context)
        pin_fields = [self.parameterAsString(parameters_, name, context)
                      for name in (PIN_COL_FIELD, PIN_ROW_FIELD)]
        if ok and sum(bool(f) for f in pin_fields) == 1:
            return False, "Pin column and pin row go together: set both fields or neither"
        if ok and self.options:
            import snakegrid

            values = parameters.values(self, self.options, parameters_, context)
            try:
                snakegrid.check_options(**values)
            except snakegrid.SnakegridError as e:
                return False, str(e)
            if self.parameterAsFileOutput(parameters_, HEXJSON, context) and \
                    values.get("cell", "square") != "hex":
                return False, "A HexJSON file describes hexagons: set Cell shape to hex"
        return ok, message

    def process(self, sg, parameters_, context, feedback):
        source = self.parameterAsSource(parameters_, INPUT, context)
        if source is None:
            raise QgsProcessingException(self.invalidSourceError(parameters_, INPUT))
        id_field = self.parameterAsString(parameters_, ID_FIELD, context)
        group_field = self.parameterAsString(parameters_, GROUP_FIELD, context)
        label_field = self.parameterAsString(parameters_, LABEL_FIELD, context)
        pin_fields = [self.parameterAsString(parameters_, name, context)
                      for name in (PIN_COL_FIELD, PIN_ROW_FIELD)]
        options = parameters.values(self, self.options, parameters_, context)

        feedback.setProgressText("reading the layer")
        features = common.Features(source, id_field, feedback, 10.0, group_field,
                                   [f for f in pin_fields if f])
        crs, cut, pins = self.placement(sg, features, parameters_, context, feedback)
        grid = sg.layout(features.wkb(crs, context, cut), features.ids, labels=features.labels,
                         groups=features.groups, pins=pins,
                         progress=common.Progress(feedback, 10.0, 95.0), **options)
        for note in grid.notes:
            feedback.pushWarning(note)

        added = sg.fields()
        fields, kept = common.grid_fields(features.fields, added)
        sink, dest_id = self.parameterAsSink(
            parameters_, OUTPUT, context, fields, QgsWkbTypes.Polygon, crs)
        if sink is None:
            raise QgsProcessingException(self.invalidSinkError(parameters_, OUTPUT))
        for feature, cell in zip(features.features, grid.cells):
            attributes = feature.attributes()
            out = QgsFeature(fields)
            out.setAttributes([attributes[i] for i in kept] + list(cell.fields.values()))
            out.setGeometry(common.geometry_from_wkb(cell.geometry))
            if not sink.addFeature(out, QgsFeatureSink.FastInsert):
                raise QgsProcessingException(self.writeFeatureError(sink, parameters_, OUTPUT))
        results = {OUTPUT: dest_id}

        outline_fields = QgsFields()
        outline_fields.append(QgsField("regions", QVariant.Int))
        outline_sink, outline_id = self.parameterAsSink(
            parameters_, OUTLINE, context, outline_fields, QgsWkbTypes.MultiPolygon, crs)
        if outline_sink is not None:
            outline = QgsFeature(outline_fields)
            outline.setAttributes([len(grid.cells)])
            outline.setGeometry(common.geometry_from_wkb(grid.moved_outline))
            if not outline_sink.addFeature(outline, QgsFeatureSink.FastInsert):
                raise QgsProcessingException(
                    self.writeFeatureError(outline_sink, parameters_, OUTLINE))
            results[OUTLINE] = outline_id

        hexjson = self.parameterAsFileOutput(parameters_, HEXJSON, context)
        if hexjson:
            if grid.hexjson is None:
                raise QgsProcessingException("A HexJSON file describes hexagons: set Cell "
                                             "shape to hex")
            with open(hexjson, "w", encoding="utf-8") as out:
                out.write(grid.hexjson)
            results[HEXJSON] = hexjson

        label = label_field or next(
            (name for name in ("abbr", "name") if features.fields.lookupField(name) >= 0), "")
        if label and context.willLoadLayerOnCompletion(dest_id):
            context.layerToLoadOnCompletionDetails(dest_id).setPostProcessor(
                LabelCells.create(label))
        feedback.setProgress(100.0)
        feedback.pushInfo(f"{len(grid.cells)} cells of {grid.cell_size:.6g} map units in "
                          f"{crs.description() or 'planar coordinates'}.")
        results.update(common.layout_results(grid.metrics, feedback))
        if grid.group_metrics is not None:
            for name, label, attribute in GROUP_OUTPUTS:
                results[name] = getattr(grid.group_metrics, attribute)
                feedback.pushInfo(f"{label}: {results[name]:.4f}")
        return results


EDITED, KEEP_FIELD = "EDITED", "KEEP_FIELD"

RELAYOUT_ABOUT = """\
Lays a grid map out again after you edited it by hand: the cells you moved stay where you put \
them, the regions you ticked stay where they are, and every other region is laid out around them.
INPUT: the source polygons the grid map was made from; ID_FIELD: their id field, whose values \
the grid layer's features carry in the same field.
EDITED: the grid layer written by Grid map (snake model) and edited: a cell whose centre lies more \
than a quarter cell from the position its grid_q and grid_r name (for squares, grid_col and \
grid_row) was moved, to the nearest lattice position (the lattice the unmoved cells lie on); two \
cells on one position are refused, naming both. KEEP_FIELD (optional): a field of the grid layer, \
true (or non-zero) for each region to keep where it is. The output is in the grid layer's CRS; \
for the rest see Grid map (snake model).
{parameters}"""


class RelayoutAlgorithm(GridMapAlgorithm):
    """Grid map with pins read off a hand-edited grid layer."""

    def name(self):
        return "relayout"

    def displayName(self):  # noqa: N802
        return "Re-layout after hand edits"

    def shortHelpString(self):  # noqa: N802
        return library.problem() or RELAYOUT_ABOUT.format(
            parameters=parameters.help_text(self.options))

    def createInstance(self):  # noqa: N802
        return RelayoutAlgorithm()

    def add_placement_parameters(self):
        self.addParameter(QgsProcessingParameterFeatureSource(
            EDITED, "Edited grid layer", [QgsProcessing.TypeVectorPolygon]))
        self.addParameter(QgsProcessingParameterField(
            KEEP_FIELD, "Keep field of the grid layer (regions ticked to keep; optional)",
            parentLayerParameterName=EDITED, optional=True))

    def placement(self, sg, features, parameters_, context, feedback):
        edited = self.parameterAsSource(parameters_, EDITED, context)
        if edited is None:
            raise QgsProcessingException(self.invalidSourceError(parameters_, EDITED))
        id_field = self.parameterAsString(parameters_, ID_FIELD, context)
        keep_field = self.parameterAsString(parameters_, KEEP_FIELD, context)
        fields = edited.fields()
        missing = [name for name in (id_field, "grid_q", "grid_r")
                   if name and fields.lookupField(name) < 0]
        if missing:
            raise QgsProcessingException(
                f"The edited grid layer has no field {', '.join(missing)}: give the grid layer "
                "Grid map (snake model) wrote, with the source's id field")
        cells = common.Features(edited, id_field, feedback, 10.0)
        at = {name: fields.lookupField(name) for name in ("grid_q", "grid_r")}
        keep_index = common.field_index(fields, keep_field)
        q = [common._id(f.attribute(at["grid_q"])) for f in cells.features]
        r = [common._id(f.attribute(at["grid_r"])) for f in cells.features]
        keep = [keep_index >= 0 and common.ticked(f.attribute(keep_index), label)
                for f, label in zip(cells.features, cells.labels)]
        options = parameters.values(self, self.options, parameters_, context)
        crs = edited.sourceCrs()
        try:
            pins = sg.edit_pins(cells.wkb(crs, context), cells.ids, q, r, keep=keep,
                                labels=cells.labels, **options)
        except ValueError as e:
            # A cell whose grid_q or grid_r is NULL or not a whole number, named.
            raise QgsProcessingException(str(e)) from e
        by_id = {sg.id_text(i): pin for i, pin in zip(cells.ids, pins)}
        moved = sum(1 for pin in pins if pin and pin[2])
        kept = sum(1 for pin in pins if pin and not pin[2])
        feedback.pushInfo(f"{moved} moved cells and {kept} kept regions pinned; the other "
                          f"{len(pins) - moved - kept} laid out again.")
        # The regions go to the edited grid's CRS as drawn: that CRS is the user's now, and
        # the library's cut is for the CRS its own rule chose.
        return crs, None, [None if by_id.get(sg.id_text(i)) is None else by_id[sg.id_text(i)][:2]
                          for i in features.ids]
