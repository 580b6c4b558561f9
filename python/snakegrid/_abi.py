"""The C API as ctypes sees it: the structs of include/snakegrid.h and every function's signature.

This is the one mirror of the header in Python. Each struct lists its fields in the header's
order, one line each, so a field the header gains is one line here; tests/test_abi.py compiles
a C program against the header and compares every size and offset with these, so a mirror that
drifts from the header fails the tests instead of reading garbage.
"""

import ctypes

_STATUS = ctypes.c_uint32
_P = ctypes.c_void_p
_TEXT = ctypes.c_char_p
_SIZE = ctypes.c_size_t


class Option(ctypes.Structure):
    """snakegrid_option: one row of the parameter table."""

    _fields_ = [
        ("name", _TEXT),
        ("kind", ctypes.c_uint32),
        ("default_value", _TEXT),
        ("optional", ctypes.c_bool),
        ("has_minimum", ctypes.c_bool),
        ("minimum", ctypes.c_double),
        ("minimum_open", ctypes.c_bool),
        ("has_maximum", ctypes.c_bool),
        ("maximum", ctypes.c_double),
        ("maximum_open", ctypes.c_bool),
        ("range", _TEXT),
        ("integer_bits", ctypes.c_uint32),
        ("list_min", _SIZE),
        ("list_max", _SIZE),
        ("choices", _TEXT),
        ("unit", _TEXT),
        ("group", _TEXT),
        ("group_title", _TEXT),
        ("advanced", ctypes.c_bool),
        ("summary", _TEXT),
        ("help", _TEXT),
    ]


class Field(ctypes.Structure):
    """snakegrid_field: one field a grid layer adds."""

    _fields_ = [
        ("name", _TEXT),
        ("integer", ctypes.c_bool),
        ("description", _TEXT),
    ]


class RegionMetrics(ctypes.Structure):
    """snakegrid_region_metrics."""

    _fields_ = [
        ("displacement", ctypes.c_double),
        ("neighbours_kept", ctypes.c_double),
        ("orientation_error", ctypes.c_double),
    ]


class LayoutMetrics(ctypes.Structure):
    """snakegrid_layout_metrics (it grows: add each new field here, in the header's order)."""

    _fields_ = [
        ("location", ctypes.c_double),
        ("location_p90", ctypes.c_double),
        ("location_max", ctypes.c_double),
        ("location_raw", ctypes.c_double),
        ("location_moved", ctypes.c_double),
        ("adjacent", ctypes.c_double),
        ("adjacent_rook", ctypes.c_double),
        ("false_neighbours", ctypes.c_double),
        ("orientation", ctypes.c_double),
        ("misdirected", ctypes.c_double),
        ("shape", ctypes.c_double),
        ("source_holes", ctypes.c_double),
        ("wrong_landmass", ctypes.c_double),
        ("pieces", ctypes.c_uint32),
        ("source_pieces", ctypes.c_uint32),
        ("holes", ctypes.c_uint32),
        ("notches", ctypes.c_uint32),
    ]


class GroupMetrics(ctypes.Structure):
    """snakegrid_group_metrics."""

    _fields_ = [
        ("whole", ctypes.c_double),
        ("adjacency", ctypes.c_double),
        ("orientation", ctypes.c_double),
        ("groups", ctypes.c_uint32),
        ("blocks", ctypes.c_uint32),
        ("contacts", ctypes.c_uint32),
        ("group_pairs", ctypes.c_uint32),
        ("reach", ctypes.c_uint32),
    ]


class EditPin(ctypes.Structure):
    """snakegrid_edit_pin."""

    _fields_ = [
        ("pinned", ctypes.c_bool),
        ("moved", ctypes.c_bool),
        ("col", ctypes.c_int32),
        ("row", ctypes.c_int32),
    ]


#: Every mirrored struct under its C name, for the layout test.
STRUCTS = {
    "snakegrid_option": Option,
    "snakegrid_field": Field,
    "snakegrid_region_metrics": RegionMetrics,
    "snakegrid_layout_metrics": LayoutMetrics,
    "snakegrid_group_metrics": GroupMetrics,
    "snakegrid_edit_pin": EditPin,
}

#: snakegrid_option_kind values, by position.
OPTION_KINDS = ("real", "integer", "bool", "choice", "real_list", "pair_list")

#: snakegrid_status values the package treats specially.
STATUS_CANCELLED = 7

PROGRESS = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.c_double, _TEXT, _P)

_OUT_P = ctypes.POINTER(_P)
_OUT_SIZE = ctypes.POINTER(_SIZE)
_OUT_I32 = ctypes.POINTER(ctypes.c_int32)
_OUT_DOUBLE = ctypes.POINTER(ctypes.c_double)
_OUT_TEXT = ctypes.POINTER(_TEXT)
_OUT_BYTES = ctypes.POINTER(ctypes.POINTER(ctypes.c_uint8))
_WKB = ctypes.c_char_p

#: Every function the package calls: name -> (restype, argtypes).
SIGNATURES = {
    "snakegrid_version": (_TEXT, []),
    "snakegrid_last_error_message": (_TEXT, []),
    "snakegrid_option_count": (_SIZE, []),
    "snakegrid_option_info": (_STATUS, [_SIZE, ctypes.POINTER(Option)]),
    "snakegrid_options_new": (_STATUS, [_OUT_P]),
    "snakegrid_options_free": (None, [_P]),
    "snakegrid_options_set": (_STATUS, [_P, _TEXT, _TEXT]),
    "snakegrid_regions_new": (_STATUS, [_OUT_P]),
    "snakegrid_regions_free": (None, [_P]),
    "snakegrid_regions_add": (_STATUS, [_P, _TEXT, _WKB, _SIZE]),
    "snakegrid_regions_add_feature": (_STATUS, [_P, _TEXT, _TEXT, _WKB, _SIZE]),
    "snakegrid_regions_set_group": (_STATUS, [_P, _SIZE, _TEXT]),
    "snakegrid_regions_set_pin": (_STATUS, [_P, _SIZE, ctypes.c_double, ctypes.c_double]),
    "snakegrid_edit_pins": (
        _STATUS,
        [_P, ctypes.POINTER(ctypes.c_int32), ctypes.POINTER(ctypes.c_int32),
         ctypes.POINTER(ctypes.c_bool), _SIZE, _P, ctypes.POINTER(EditPin)],
    ),
    "snakegrid_run": (_STATUS, [_P, _P, PROGRESS, _P, _OUT_P]),
    "snakegrid_result_free": (None, [_P]),
    "snakegrid_result_count": (_STATUS, [_P, _OUT_SIZE]),
    "snakegrid_result_cell_size": (_STATUS, [_P, _OUT_DOUBLE]),
    "snakegrid_result_region_id": (_STATUS, [_P, _SIZE, _OUT_TEXT]),
    "snakegrid_result_region_repair": (_STATUS, [_P, _SIZE, _OUT_TEXT]),
    "snakegrid_result_cell_wkb": (_STATUS, [_P, _SIZE, _OUT_BYTES, _OUT_SIZE]),
    "snakegrid_result_region_metrics": (_STATUS, [_P, _SIZE, ctypes.POINTER(RegionMetrics)]),
    "snakegrid_result_layout_metrics": (_STATUS, [_P, ctypes.POINTER(LayoutMetrics)]),
    "snakegrid_result_group_metrics": (_STATUS, [_P, ctypes.POINTER(GroupMetrics)]),
    "snakegrid_result_moved_outline_wkb": (_STATUS, [_P, _OUT_BYTES, _OUT_SIZE]),
    "snakegrid_result_note_count": (_STATUS, [_P, _OUT_SIZE]),
    "snakegrid_result_note": (_STATUS, [_P, _SIZE, _OUT_TEXT]),
    "snakegrid_result_hexjson": (_STATUS, [_P, _OUT_TEXT]),
    "snakegrid_field_count": (_SIZE, []),
    "snakegrid_field_info": (_STATUS, [_SIZE, ctypes.POINTER(Field)]),
    "snakegrid_result_field": (_STATUS, [_P, _SIZE, _SIZE, _OUT_DOUBLE]),
    "snakegrid_score": (
        _STATUS,
        [_P, _P, ctypes.POINTER(LayoutMetrics), ctypes.POINTER(RegionMetrics), _SIZE],
    ),
    "snakegrid_working_crs": (_STATUS, [ctypes.POINTER(ctypes.c_double), _SIZE, _OUT_P]),
    "snakegrid_crs_free": (None, [_P]),
    "snakegrid_crs_wkt": (_STATUS, [_P, _OUT_TEXT]),
    "snakegrid_crs_name": (_STATUS, [_P, _OUT_TEXT]),
    "snakegrid_crs_note": (_STATUS, [_P, _OUT_TEXT]),
    "snakegrid_lon_lat_boxes": (
        _STATUS,
        [ctypes.POINTER(ctypes.c_uint8), _SIZE,
         ctypes.POINTER(ctypes.POINTER(ctypes.c_double)), _OUT_SIZE],
    ),
    "snakegrid_crs_cut": (
        _STATUS, [_P, ctypes.POINTER(ctypes.c_uint8), _SIZE, _OUT_BYTES, _OUT_SIZE],
    ),
    "snakegrid_projected_crs_note": (_STATUS, [_TEXT, _TEXT, _OUT_TEXT]),
    "snakegrid_looks_like_degrees": (
        _STATUS,
        [ctypes.POINTER(ctypes.c_double), _SIZE, ctypes.POINTER(ctypes.c_bool)],
    ),
}
