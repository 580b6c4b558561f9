"""Grid map metrics: scores an existing grid layer (perhaps edited by hand) against its regions."""

from qgis.core import (
    QgsFeature,
    QgsFeatureSink,
    QgsProcessing,
    QgsProcessingException,
    QgsProcessingParameterFeatureSink,
    QgsProcessingParameterFeatureSource,
    QgsProcessingParameterField,
    QgsWkbTypes,
)

from .. import binding
from . import common

REGIONS, REGION_ID, GRID, GRID_ID, OUTPUT = "REGIONS", "REGION_ID", "GRID", "GRID_ID", "OUTPUT"

#: The per-region metrics rewritten on the grid layer (its column and row are left as they are).
SCORED_FIELDS = common.GRID_FIELDS[2:]


class GridMetricsAlgorithm(common.SnakegridAlgorithm):
    def name(self):
        return "gridmetrics"

    def displayName(self):  # noqa: N802 (QGIS's names throughout)
        return "Grid map metrics"

    def createInstance(self):  # noqa: N802
        return GridMetricsAlgorithm()

    def shortHelpString(self):  # noqa: N802
        fields = "".join(f"<li><b>{name}</b>: {meaning}</li>" for name, _, meaning in SCORED_FIELDS)
        metrics = "".join(f"<li>{label}</li>" for _, label, _ in common.LAYOUT_OUTPUTS)
        return (
            "<p>Scores a grid map against its regions with the metrics of <i>Grid map (snake "
            "model)</i>, so that a layout edited by hand, or made by another tool, can be "
            "compared with the method's on equal terms.</p>"
            "<p><b>Regions</b>: the source polygon layer, and its <b>region id field</b> "
            "(default: the feature id). <b>Grid layer</b>: one square cell per region, and its "
            "<b>grid id field</b> holding the region's id (default: the field named like the "
            "region id field). Every region needs exactly one cell and every cell a region; the "
            "error names the id otherwise. Columns and rows are recovered from the cell "
            "centres and the mean cell side. The regions are projected to the grid layer's CRS "
            "(a geographic grid layer to Lambert azimuthal equal-area centred on it).</p>"
            f"<p><b>Scored grid map</b>: the grid layer with its fields, and</p><ul>{fields}</ul>"
            f"<p>Numeric outputs, the layout metrics:</p><ul>{metrics}</ul>"
        )

    def initAlgorithm(self, config=None):  # noqa: N802
        self.addParameter(QgsProcessingParameterFeatureSource(
            REGIONS, "Regions (source polygons)", [QgsProcessing.TypeVectorPolygon]))
        self.addParameter(QgsProcessingParameterField(
            REGION_ID, "Region id field (default: the feature id)",
            parentLayerParameterName=REGIONS, optional=True))
        self.addParameter(QgsProcessingParameterFeatureSource(
            GRID, "Grid layer (one square per region)", [QgsProcessing.TypeVectorPolygon]))
        self.addParameter(QgsProcessingParameterField(
            GRID_ID, "Grid id field (default: named like the region id field)",
            parentLayerParameterName=GRID, optional=True))
        self.addParameter(QgsProcessingParameterFeatureSink(
            OUTPUT, "Scored grid map", QgsProcessing.TypeVectorPolygon))
        common.add_layout_outputs(self)

    def processAlgorithm(self, parameters, context, feedback):  # noqa: N802
        library = common.library()
        regions_source = self.parameterAsSource(parameters, REGIONS, context)
        grid_source = self.parameterAsSource(parameters, GRID, context)
        for source, name in ((regions_source, REGIONS), (grid_source, GRID)):
            if source is None:
                raise QgsProcessingException(self.invalidSourceError(parameters, name))
        region_id = self.parameterAsString(parameters, REGION_ID, context)
        grid_id = self.parameterAsString(parameters, GRID_ID, context) or region_id
        regions = common.Regions(regions_source, region_id, "The regions layer", feedback, 20.0)
        cells = common.Regions(grid_source, grid_id, "The grid layer", feedback, 40.0)
        crs = common.working_crs(cells.crs, cells.extent(), feedback)
        feedback.setProgressText("Scoring")
        cell_wkb = cells.wkb(crs, context)
        try:
            layout, per_region = library.score(regions.wkb(crs, context), cell_wkb)
        except binding.SnakegridError as e:
            raise common.library_failure(e) from e
        feedback.setProgress(90.0)

        by_id = dict(zip(regions.ids, per_region))
        fields, kept = common.grid_fields(cells.fields, SCORED_FIELDS)
        sink, dest_id = self.parameterAsSink(
            parameters, OUTPUT, context, fields, QgsWkbTypes.flatType(grid_source.wkbType()), crs)
        if sink is None:
            raise QgsProcessingException(self.invalidSinkError(parameters, OUTPUT))
        for feature, (cell_id, wkb) in zip(cells.features, cell_wkb):
            m = by_id[cell_id]
            attributes = feature.attributes()
            out = QgsFeature(fields)
            out.setAttributes([attributes[i] for i in kept] + [
                m.displacement, m.neighbours_kept, m.orientation_error])
            out.setGeometry(common.geometry_from_wkb(wkb))
            if not sink.addFeature(out, QgsFeatureSink.FastInsert):
                raise QgsProcessingException(self.writeFeatureError(sink, parameters, OUTPUT))
        feedback.setProgress(100.0)
        results = {OUTPUT: dest_id}
        results.update(common.layout_results(layout, feedback))
        return results

