"""What the two algorithms share: the library, the working CRS, reading regions as WKB, progress,
and the fields and numeric outputs they write. No part of the method lives here."""

from qgis.core import (
    QgsCoordinateReferenceSystem,
    QgsProcessingAlgorithm,
    QgsCoordinateTransform,
    QgsField,
    QgsFields,
    QgsGeometry,
    QgsProcessingException,
    QgsProcessingOutputNumber,
    QgsRectangle,
    QgsWkbTypes,
)
from qgis.PyQt.QtCore import QVariant

from .. import binding

#: The fields a grid layer adds after the source's, as the command line writes them
#: (src/io/write.rs): name, type, meaning.
GRID_FIELDS = [
    ("grid_col", QVariant.Int, "column of the cell, from the left (0 = leftmost used column)"),
    ("grid_row", QVariant.Int, "row of the cell, from the top (0 = topmost used row)"),
    ("cell_disp", QVariant.Double, "distance from the region to its cell, in cells"),
    ("nbr_kept", QVariant.Double, "share of the region's neighbours whose cells still touch"),
    ("orient_err", QVariant.Double, "mean direction error towards its neighbours, degrees"),
]

#: The four layout metrics (method.md section 8) as numeric outputs: output name, label,
#: binding.LayoutMetrics attribute.
LAYOUT_OUTPUTS = [
    ("C_LOCATION", "C_location: mean distance region to cell, cells (lower is better)",
     "location"),
    ("C_ADJACENT", "C_adjacent: share of neighbour pairs kept (higher is better)", "adjacent"),
    ("C_ORIENTATION", "C_orientation: mean direction error, degrees (lower is better)",
     "orientation"),
    ("C_SHAPE", "C_shape: outline similarity, 0-1 (higher is better)", "shape"),
]


class SnakegridAlgorithm(QgsProcessingAlgorithm):
    """What every snakegrid algorithm does alike: no group, and no run without the library."""

    def group(self):
        return ""

    def groupId(self):  # noqa: N802 (QGIS's name)
        return ""

    def canExecute(self):  # noqa: N802
        # QGIS shows this message in the dialog instead of running.
        try:
            binding.load()
        except binding.LibraryError as e:
            return False, str(e)
        return True, ""


def add_layout_outputs(algorithm):
    for name, label, _ in LAYOUT_OUTPUTS:
        algorithm.addOutput(QgsProcessingOutputNumber(name, label))


def layout_results(metrics, feedback):
    """The numeric outputs of `metrics`, also logged."""
    results = {}
    for name, label, attribute in LAYOUT_OUTPUTS:
        results[name] = getattr(metrics, attribute)
        feedback.pushInfo(f"{label}: {results[name]:.4f}")
    return results


def library():
    """The loaded library; a missing or incompatible one is a QgsProcessingException whose
    message says what to do, which QGIS shows instead of a traceback."""
    try:
        return binding.load()
    except binding.LibraryError as e:
        raise QgsProcessingException(str(e)) from e


def library_failure(error):
    """A library error as QGIS reports algorithm failures, with the library's message."""
    return QgsProcessingException(str(error))


def grid_fields(source_fields, added=GRID_FIELDS):
    """The source's fields, then `added` (rows of GRID_FIELDS); a source field of the same name
    (a grid layer made or scored again) gives way to the new one. Returns the fields and the
    indices of the source fields kept."""
    names = {name.lower() for name, _, _ in added}
    fields = QgsFields()
    kept = []
    for i, field in enumerate(source_fields):
        if field.name().lower() not in names:
            fields.append(field)
            kept.append(i)
    for name, kind, _ in added:
        fields.append(QgsField(name, kind))
    return fields, kept


def check_polygons(source, what):
    """Refuses a layer that is not a polygon layer, naming its geometry type."""
    kind = QgsWkbTypes.geometryType(source.wkbType())
    if kind != QgsWkbTypes.PolygonGeometry:
        raise QgsProcessingException(
            f"{what} must be a polygon layer; this one has "
            f"{QgsWkbTypes.displayString(source.wkbType()) or 'no'} geometries."
        )


class Regions:
    """The features of a polygon source, with each one's id and geometry as they will be given to
    the library (in the working CRS, as WKB)."""

    def __init__(self, source, id_field, what, feedback, progress_to=10.0):
        """Reads `source` (a QgsProcessingFeatureSource). `id_field` empty means the feature
        id, as on the command line. Progress goes from 0 to `progress_to` percent."""
        check_polygons(source, what)
        self.crs = source.sourceCrs()
        self.fields = source.fields()
        self.features = []
        self.ids = []
        self.geometries = []
        id_index = self.fields.lookupField(id_field) if id_field else -1
        total = max(source.featureCount(), 1)
        for n, feature in enumerate(source.getFeatures()):
            if feedback.isCanceled():
                raise QgsProcessingException("Cancelled.")
            region_id = _text(feature.attribute(id_index)) if id_index >= 0 else str(feature.id())
            if region_id is None:
                raise QgsProcessingException(
                    f"{what}: feature {feature.id()} has no value in the id field {id_field}."
                )
            geometry = feature.geometry()
            if geometry.isNull() or geometry.isEmpty():
                raise QgsProcessingException(f"{what}: feature {region_id} has no geometry.")
            if QgsWkbTypes.geometryType(geometry.wkbType()) != QgsWkbTypes.PolygonGeometry:
                raise QgsProcessingException(
                    f"{what}: feature {region_id} is a "
                    f"{QgsWkbTypes.displayString(geometry.wkbType())}, not a polygon."
                )
            if QgsWkbTypes.isCurvedType(geometry.wkbType()):
                # The C API reads Polygon and MultiPolygon WKB only.
                geometry = QgsGeometry(geometry.constGet().segmentize())
            self.features.append(feature)
            self.ids.append(region_id)
            self.geometries.append(geometry)
            feedback.setProgress(progress_to * (n + 1) / total)
        if not self.features:
            raise QgsProcessingException(f"{what} has no features to lay out.")

    def extent(self):
        box = QgsRectangle()
        box.setMinimal()
        for geometry in self.geometries:
            box.combineExtentWith(geometry.boundingBox())
        return box

    def wkb(self, working_crs, context):
        """(id, WKB) pairs in `working_crs`."""
        transform = None
        if self.crs.isValid() and working_crs != self.crs:
            transform = QgsCoordinateTransform(self.crs, working_crs, context.transformContext())
        pairs = []
        for region_id, geometry in zip(self.ids, self.geometries):
            if transform is not None:
                geometry = QgsGeometry(geometry)
                geometry.transform(transform)
            pairs.append((region_id, bytes(geometry.asWkb())))
        return pairs


def working_crs(crs, extent, feedback):
    """The CRS the method works in, as on the command line: the layer's if it is projected, else
    a Lambert azimuthal equal-area CRS centred on the features' extent (in degrees)."""
    if not crs.isValid():
        feedback.pushWarning("The layer has no CRS: its coordinates are taken as planar.")
        return crs
    if not crs.isGeographic():
        return crs
    lon, lat = extent.center().x(), extent.center().y()
    # Six decimals (about 0.1 m), the command line's definition to the character.
    definition = f"+proj=laea +lat_0={lat:.6f} +lon_0={lon:.6f} +datum=WGS84 +units=m +no_defs"
    working = QgsCoordinateReferenceSystem.fromProj(definition)
    if not working.isValid():
        raise QgsProcessingException(f"Cannot make the working CRS {definition}.")
    feedback.pushInfo(
        f"The layer's CRS {crs.authid() or crs.description()} is geographic: working in "
        f"Lambert azimuthal equal-area centred on the layer ({definition})."
    )
    return working


def geometry_from_wkb(wkb):
    geometry = QgsGeometry()
    geometry.fromWkb(wkb)
    return geometry


def _text(value):
    """An attribute as an id: None for NULL, integral numbers without a decimal part."""
    if value is None or (hasattr(value, "isNull") and value.isNull()):
        return None
    if isinstance(value, float) and value.is_integer():
        return str(int(value))
    return str(value)


class Progress:
    """The library's progress callback driving a QgsProcessingFeedback between two percentages;
    answers "stop" once the user cancels. The library calls it from worker threads, one call at
    a time; QgsProcessingFeedback may be updated from any thread."""

    def __init__(self, feedback, start, end):
        self.feedback, self.start, self.end = feedback, start, end
        self.message = None

    def __call__(self, fraction, message):
        if self.feedback.isCanceled():
            return False
        self.feedback.setProgress(self.start + (self.end - self.start) * fraction)
        if message != self.message:
            self.message = message
            self.feedback.setProgressText(message)
        return True
