"""What the two algorithms share: the package, reading a layer's features for the library, the
working CRS, progress and cancelling, and writing the fields the library lists. The policy
(checks and messages, CRS rule, field names) is the library's; this module only carries it
into QGIS."""

import os

from qgis.core import (
    QgsCoordinateReferenceSystem,
    QgsCoordinateTransform,
    QgsCsException,
    QgsFeatureRequest,
    QgsField,
    QgsFields,
    QgsGeometry,
    QgsProcessingAlgorithm,
    QgsProcessingException,
    QgsProcessingFeatureSource,
    QgsProcessingOutputNumber,
    QgsWkbTypes,
)
from qgis.PyQt.QtCore import QVariant
from qgis.PyQt.QtGui import QIcon

from .. import library

ICON = os.path.join(os.path.dirname(os.path.dirname(__file__)), "icon.svg")
HELP_URL = f"{library.HOME}/blob/main/docs/qgis-plugin.md"

#: The four layout metrics (method.md section 8) as numeric outputs: output name, label,
#: snakegrid.LayoutMetrics attribute.
LAYOUT_OUTPUTS = [
    ("C_LOCATION", "C_location: mean distance region to cell, cells (lower is better)",
     "location"),
    ("C_ADJACENT", "C_adjacent: share of neighbour pairs kept (higher is better)", "adjacent"),
    ("C_ORIENTATION", "C_orientation: mean direction error, degrees (lower is better)",
     "orientation"),
    ("C_SHAPE", "C_shape: outline similarity, 0-1 (higher is better)", "shape"),
]


class Cancelled(Exception):
    """The user cancelled: the algorithm returns no outputs, which QGIS does not show as a
    failure (raising QgsProcessingException would print "Execution failed" in red)."""


class SnakegridAlgorithm(QgsProcessingAlgorithm):
    """What every snakegrid algorithm does alike."""

    def group(self):
        return "Grid maps"

    def groupId(self):  # noqa: N802 (QGIS's names throughout)
        return "gridmaps"

    def tags(self):
        return ["grid map", "tile map", "cartogram", "hexagon", "square", "tessellation",
                "snake model", "equal area"]

    def icon(self):
        return QIcon(ICON)

    def svgIconPath(self):
        return ICON

    def helpUrl(self):
        return HELP_URL

    def canExecute(self):
        # QGIS shows this message in the dialog instead of running.
        message = library.problem()
        return (False, message) if message else (True, "")

    def processAlgorithm(self, parameters, context, feedback):
        sg = library.package()
        try:
            return self.process(sg, parameters, context, feedback)
        except (Cancelled, sg.Cancelled):
            feedback.pushWarning("Cancelled")
            return {}
        except sg.SnakegridError as e:
            raise QgsProcessingException(str(e)) from e


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


def grid_fields(source_fields, added):
    """The source's fields, then `added` (snakegrid.Field rows); a source field of the same name
    (a grid layer made or scored again) gives way to the new one. Returns the fields and the
    indices of the source fields kept."""
    names = {field.name.lower() for field in added}
    fields = QgsFields()
    kept = []
    for i, field in enumerate(source_fields):
        if field.name().lower() not in names:
            fields.append(field)
            kept.append(i)
    for field in added:
        kind = QVariant.Int if field.integer else QVariant.Double
        fields.append(QgsField(field.name, kind, comment=field.description))
    return fields, kept


def _id(value):
    """An attribute as the package takes an id: None for QGIS's NULL, else the value (the
    package writes whole floats as the command line does)."""
    if value is None or (hasattr(value, "isNull") and value.isNull()):
        return None
    return value


def _number(value, label):
    """A pin attribute as a number (None for NULL or blank), or a clear error naming the
    feature; the library checks that it is whole."""
    value = _id(value)
    if value is None or (isinstance(value, str) and not value.strip()):
        return None
    try:
        return float(value)
    except (TypeError, ValueError):
        raise QgsProcessingException(f"feature {label}: the pin value {value!r} is not a "
                                     "number") from None


def field_index(fields, name):
    """The index of field `name` (-1 when none is given), or a clear error: a name typed into
    qgis_process or processing.run is not checked against the layer, and a field taken as
    missing laid the map out by feature ids, without groups or pins."""
    if not name:
        return -1
    index = fields.lookupField(name)
    if index < 0:
        raise QgsProcessingException(
            f"the layer has no field {name!r} (its fields: {', '.join(fields.names())})")
    return index


def ticked(value, label):
    """A keep attribute as true or false: NULL, 0, blank and false/no/off are false, a non-zero
    number and true/yes/on are true (as text too: a text field of "false" is not kept), anything
    else a clear error naming the feature."""
    value = _id(value)
    if value is None or isinstance(value, bool):
        return bool(value)
    if isinstance(value, (int, float)):
        return value != 0
    text = str(value).strip().lower()
    if text in ("", "false", "f", "no", "n", "off"):
        return False
    if text in ("true", "t", "yes", "y", "on"):
        return True
    try:
        return float(text) != 0
    except ValueError:
        raise QgsProcessingException(f"feature {label}: the keep value {value!r} is neither "
                                     "true nor false") from None


class Features:
    """The features of a source as the library takes them: ids (the id field's values, else the
    feature ids, as on the command line), labels naming them ("FID 3") and their geometries.
    The library checks each one (snakegrid.layout and .score), with the command line's
    messages."""

    def __init__(self, source, id_field, feedback, progress_to, group_field=None,
                 pin_fields=None):
        self.crs = source.sourceCrs()
        self.fields = source.fields()
        id_index = field_index(self.fields, id_field)
        group_index = field_index(self.fields, group_field)
        self.features, self.ids, self.labels, self.geometries = [], [], [], []
        #: Each feature's group (None: NULL), or None without a group field.
        self.groups = [] if group_index >= 0 else None
        pin_indices = [field_index(self.fields, f) for f in pin_fields or ()]
        #: Each feature's pin, (column, row) with None for NULL, or None without pin fields.
        self.pins = [] if len(pin_indices) == 2 and min(pin_indices) >= 0 else None
        total = max(source.featureCount(), 1)
        # The library checks and repairs geometries as the command line does (a bow-tie is
        # repaired with a note): QGIS's own validity check would refuse them first.
        features = source.getFeatures(
            QgsFeatureRequest(), QgsProcessingFeatureSource.FlagSkipGeometryValidityChecks)
        for n, feature in enumerate(features):
            if feedback.isCanceled():
                raise Cancelled()
            self.features.append(feature)
            self.ids.append(
                _id(feature.attribute(id_index)) if id_index >= 0 else str(feature.id()))
            self.labels.append(f"FID {feature.id()}")
            if self.groups is not None:
                self.groups.append(_id(feature.attribute(group_index)))
            if self.pins is not None:
                self.pins.append(tuple(_number(feature.attribute(i), self.labels[-1])
                                       for i in pin_indices))
            geometry = feature.geometry()
            self.geometries.append(None if geometry.isNull() else geometry)
            feedback.setProgress(progress_to * (n + 1) / total)
        if not self.features:
            # Said before the working CRS is sought, whose message ("no coordinates to centre
            # a projection on") would not say why.
            raise QgsProcessingException(
                "the layer gives no features: it is empty, or 'Selected features only' is on "
                "and none is selected")

    def drawn(self):
        """Each region as drawn, for the working-CRS rule: polygons as WKB (the library reads
        each one's extent, across ±180° where a ring steps across it), other geometries (which
        the layout then refuses by name) as their boxes."""
        return [bytes(g.asWkb()) if _polygons(g) else _box(g.boundingBox())
                for g in self.geometries if g is not None and not g.isEmpty()]

    def wkb(self, crs, context, cut=None):
        """The geometries in `crs` as WKB (None for a null geometry); `cut` (the library's
        WorkingCrs.cut) readies each for the projection first."""
        transform = None
        if self.crs.isValid() and crs.isValid() and crs != self.crs:
            transform = QgsCoordinateTransform(self.crs, crs, context.transformContext())
        out = []
        for label, geometry in zip(self.labels, self.geometries):
            if geometry is not None and transform is not None:
                # Only a region the library cuts is rebuilt; the rest are projected as read.
                drawn = bytes(geometry.asWkb()) if cut is not None and _polygons(geometry) else None
                ready = drawn if drawn is None else cut(drawn)
                geometry = QgsGeometry(geometry) if ready is drawn else geometry_from_wkb(ready)
                try:
                    geometry.transform(transform)
                except QgsCsException as e:
                    raise QgsProcessingException(
                        f"feature {label}: cannot project the geometry to "
                        f"{crs.description()}: {e}") from e
            out.append(None if geometry is None else bytes(geometry.asWkb()))
        return out


def working_crs(sg, features, target, feedback):
    """The CRS to lay out in, as the command line's -t_srs decides: `target` when valid, else
    the layer's own when projected, else the library's equal-area rule for the features as
    drawn, made from its named WKT2 (QGIS then shows its name; nothing is saved to the
    user's CRS database); and, for the rule's CRS, the library's cut that readies each region
    for it (else None). Warns as the command line notes: a layer without a CRS whose
    coordinates could be degrees, a layer in a Mercator projection (the library decides both)."""
    source = features.crs
    if target.isValid():
        if not source.isValid():
            raise QgsProcessingException(
                f"The layer has no CRS, so it cannot be projected to {target.authid()}.")
        if target.isGeographic():
            feedback.pushWarning(
                f"The target CRS {target.authid()} is geographic: the cells are squares in "
                "degrees.")
        return target, None
    if not source.isValid():
        message = "The layer has no CRS: its coordinates are taken as planar."
        if sg.looks_like_degrees(features.drawn()):
            message += (" They lie within ±180 and ±90, as longitudes and latitudes would: if "
                        "they are, set the layer's CRS (EPSG:4326 or their own geographic CRS) "
                        "first.")
        feedback.pushWarning(message)
        return source, None
    if not source.isGeographic():
        # A Mercator layer is weighed by its drawn areas: the library says when and why.
        note = sg.projected_crs_note(source.projectionAcronym() or "",
                                     source.authid() or source.description())
        if note:
            feedback.pushWarning(note[0].upper() + note[1:] + ".")
        return source, None
    chosen = sg.working_crs(features.drawn())
    crs = QgsCoordinateReferenceSystem.fromWkt(chosen.wkt)
    if not crs.isValid():
        raise QgsProcessingException(f"QGIS cannot read the working CRS {chosen.wkt}")
    feedback.pushInfo(
        f"The layer's CRS {source.authid() or source.description()} is geographic: "
        f"{chosen.note}.")
    return crs, chosen.cut


def _polygons(geometry):
    """Whether the library reads `geometry` (the layout refuses others by name); it
    linearises curved polygons itself, as the command line does."""
    return QgsWkbTypes.flatType(geometry.wkbType()) in (
        QgsWkbTypes.Polygon, QgsWkbTypes.MultiPolygon, QgsWkbTypes.CurvePolygon,
        QgsWkbTypes.MultiSurface)


def _box(rectangle):
    return (rectangle.xMinimum(), rectangle.yMinimum(), rectangle.xMaximum(),
            rectangle.yMaximum())


def geometry_from_wkb(wkb):
    geometry = QgsGeometry()
    geometry.fromWkb(wkb)
    return geometry


class Progress:
    """The library's progress callback driving a QgsProcessingFeedback between two percentages,
    with each named stage as the progress text (which the log shows); answers "stop" once the
    user cancels. The library calls it from worker threads, one call at a time;
    QgsProcessingFeedback may be updated from any thread."""

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
