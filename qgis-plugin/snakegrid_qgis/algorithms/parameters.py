"""The method's parameters as Processing parameters, made at load time from the library's table
(snakegrid.options()): names in upper case, widgets limited to the table's ranges, defaults,
help and the advanced flag from the table. Nothing about a parameter is written here."""

from qgis.core import (
    QgsProcessingParameterBoolean,
    QgsProcessingParameterDefinition,
    QgsProcessingParameterEnum,
    QgsProcessingParameterNumber,
    QgsProcessingParameterString,
)


def parameter_name(option):
    return option.name.upper()


def _is_text(option):
    # A 64-bit integer (the seed) is a string parameter: QGIS's Integer widget holds 32 bits
    # and a Double only 53, so either would refuse or round seeds users may give; the library
    # parses the text and refuses a bad one by name (checkParameterValues).
    return option.kind in ("real_list", "pair_list") or (
        option.kind == "integer" and option.integer_bits > 32)


def definition(option):
    """The Processing parameter for one row of the table."""
    name = parameter_name(option)
    label = option.summary + (f" [{option.unit}]" if option.unit else "")
    if _is_text(option):
        parameter = QgsProcessingParameterString(name, label, option.default)
    elif option.kind in ("real", "integer"):
        integer = option.kind == "integer"
        parameter = QgsProcessingParameterNumber(
            name, label,
            QgsProcessingParameterNumber.Integer if integer else QgsProcessingParameterNumber.Double,
            None if option.optional and option.default == "none" else float(option.default),
            optional=option.optional)
        # Open ends cannot be a widget's limit: the bound is, and the library refuses the bound
        # itself by name.
        if option.minimum is not None:
            parameter.setMinimum(option.minimum)
        if option.maximum is not None:
            parameter.setMaximum(option.maximum)
    elif option.kind == "bool":
        parameter = QgsProcessingParameterBoolean(name, label, option.default == "true")
    else:  # choice: the names themselves are the values, as on the command line
        parameter = QgsProcessingParameterEnum(
            name, label, list(option.choices), defaultValue=option.default,
            usesStaticStrings=True)
    if option.advanced:
        parameter.setFlags(parameter.flags() | QgsProcessingParameterDefinition.FlagAdvanced)
    parameter.setHelp(f"{option.help} Range: {option.range}; default: {option.default}.")
    return parameter


def values(algorithm, options, parameters, context):
    """{option name: value} for the library from the algorithm's parameter values; an unset
    optional parameter is left out (the library's default)."""
    out = {}
    for option in options:
        name = parameter_name(option)
        if option.optional and parameters.get(name) in (None, ""):
            continue
        if _is_text(option):
            out[option.name] = algorithm.parameterAsString(parameters, name, context).strip()
        elif option.kind == "real":
            out[option.name] = algorithm.parameterAsDouble(parameters, name, context)
        elif option.kind == "integer":
            out[option.name] = algorithm.parameterAsInt(parameters, name, context)
        elif option.kind == "bool":
            out[option.name] = algorithm.parameterAsBoolean(parameters, name, context)
        else:
            out[option.name] = algorithm.parameterAsEnumString(parameters, name, context)
    return out


def help_text(options):
    """The parameters for the help panel and `qgis_process help`, as plain text by group."""
    lines, group = [], None
    for option in options:
        if option.group_title != group:
            group = option.group_title
            lines.append(f"{group}:")
        lines.append(f"{parameter_name(option)} (default {option.default}, {option.range}"
                     f"{', ' + option.unit if option.unit else ''}): {option.summary}. "
                     f"{option.help}")
    return "\n".join(lines)
