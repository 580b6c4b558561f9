"""Grid map metrics: scores an existing grid layer (perhaps edited by hand) against its regions."""

from qgis.core import (
    QgsCoordinateReferenceSystem,
    QgsFeature,
    QgsFeatureSink,
    QgsProcessing,
    QgsProcessingException,
    QgsProcessingParameterFeatureSink,
    QgsProcessingParameterFeatureSource,
    QgsProcessingParameterField,
    QgsWkbTypes,
)

from . import common

REGIONS, REGION_ID, GRID, GRID_ID, OUTPUT = "REGIONS", "REGION_ID", "GRID", "GRID_ID", "OUTPUT"

#: The added fields a score rewrites, and the snakegrid.RegionMetrics attribute each holds. A
#: stopgap: snakegrid_score gives metrics, not field values; once the library offers a score
#: result that snakegrid_result_field reads, this table goes.
SCORED = {"cell_disp": "displacement", "nbr_kept": "neighbours_kept",
          "orient_err": "orientation_error"}

HELP = """\
Scores a grid map against its regions with the metrics of Grid map (snake model), so that a \
layout edited by hand, or made by another tool, can be compared with the method's on equal terms.
REGIONS: the source polygon layer, and REGION_ID its id field (default: the feature id).
GRID: one square or hexagonal cell per region, and GRID_ID its field holding the region's id (default: the \
field named like REGION_ID). Every region needs exactly one cell and every cell a region; the \
error names the id otherwise. Columns and rows are recovered from the cell centres and the mean \
cell side. The regions are projected to the grid layer's CRS.
OUTPUT: the grid layer with its fields, and {fields} recomputed.
Numeric outputs, the layout metrics: {metrics}."""


class GridMetricsAlgorithm(common.SnakegridAlgorithm):
    def name(self):
        return "gridmetrics"

    def displayName(self):  # noqa: N802 (QGIS's names throughout)
        return "Grid map metrics"

    def createInstance(self):  # noqa: N802
        return GridMetricsAlgorithm()

    def shortHelpString(self):  # noqa: N802
        return HELP.format(fields=", ".join(SCORED),
                           metrics=", ".join(label for _, label, _ in common.LAYOUT_OUTPUTS))

    def initAlgorithm(self, config=None):  # noqa: N802
        self.addParameter(QgsProcessingParameterFeatureSource(
            REGIONS, "Regions (source polygons)", [QgsProcessing.TypeVectorPolygon]))
        self.addParameter(QgsProcessingParameterField(
            REGION_ID, "Region id field (default: the feature id)",
            parentLayerParameterName=REGIONS, optional=True))
        self.addParameter(QgsProcessingParameterFeatureSource(
            GRID, "Grid layer (one square or hexagon per region)", [QgsProcessing.TypeVectorPolygon]))
        self.addParameter(QgsProcessingParameterField(
            GRID_ID, "Grid id field (default: named like the region id field)",
            parentLayerParameterName=GRID, optional=True))
        self.addParameter(QgsProcessingParameterFeatureSink(
            OUTPUT, "Scored grid map", QgsProcessing.TypeVectorPolygon))
        common.add_layout_outputs(self)

    def process(self, sg, parameters, context, feedback):
        regions_source = self.parameterAsSource(parameters, REGIONS, context)
        grid_source = self.parameterAsSource(parameters, GRID, context)
        for source, name in ((regions_source, REGIONS), (grid_source, GRID)):
            if source is None:
                raise QgsProcessingException(self.invalidSourceError(parameters, name))
        region_id = self.parameterAsString(parameters, REGION_ID, context)
        grid_id = self.parameterAsString(parameters, GRID_ID, context) or region_id
        regions = common.Features(regions_source, region_id, feedback, 20.0)
        cells = common.Features(grid_source, grid_id, feedback, 40.0)
        crs, cut = common.working_crs(sg, cells, QgsCoordinateReferenceSystem(), feedback)
        feedback.setProgressText("scoring")
        cell_wkb = cells.wkb(crs, context, cut)
        layout, per_region = sg.score(
            regions.wkb(crs, context, cut), regions.ids, cell_wkb, cells.ids,
            region_labels=regions.labels, cell_labels=cells.labels)
        feedback.setProgress(90.0)

        by_id = dict(zip((sg.id_text(i) for i in regions.ids), per_region))
        scored = [f for f in sg.fields() if f.name in SCORED]
        fields, kept = common.grid_fields(cells.fields, scored)
        sink, dest_id = self.parameterAsSink(
            parameters, OUTPUT, context, fields, QgsWkbTypes.flatType(grid_source.wkbType()), crs)
        if sink is None:
            raise QgsProcessingException(self.invalidSinkError(parameters, OUTPUT))
        for feature, cell_id, wkb in zip(cells.features, cells.ids, cell_wkb):
            metrics = by_id[sg.id_text(cell_id)]
            attributes = feature.attributes()
            out = QgsFeature(fields)
            out.setAttributes([attributes[i] for i in kept]
                              + [getattr(metrics, SCORED[f.name]) for f in scored])
            out.setGeometry(common.geometry_from_wkb(wkb))
            if not sink.addFeature(out, QgsFeatureSink.FastInsert):
                raise QgsProcessingException(self.writeFeatureError(sink, parameters, OUTPUT))
        feedback.setProgress(100.0)
        results = {OUTPUT: dest_id}
        results.update(common.layout_results(layout, feedback))
        return results
