# SPDX-License-Identifier: Apache-2.0
"""The dictionaries of the two recorded CANopenNode devices, as their EDS files give them (the
objects, types, access, PDO mapping and defaults, which the tester's requests follow), for
replaying their traces (canopennode_traces.py) without the upstream files in the repository.

- :func:`canopend_eds`: CANopenNode's example DS301 profile (no manufacturer objects);
- :func:`demodevice_eds`: CANopenDemo's demoDevice.eds (CANopenDemo ae81d72): the profile
  plus the demo's manufacturer objects 0x2100..0x2122 and the CiA 401 I/O 0x6000..0x6411.
"""

from __future__ import annotations

U8, U16, U32, I16, I32 = "0x0005", "0x0006", "0x0007", "0x0003", "0x0004"
I64, U64, R32, R64 = "0x0015", "0x001B", "0x0008", "0x0011"
VSTRING, OSTRING, DOMAIN = "0x0009", "0x000A", "0x000F"


def _section(name: str, keys: list[tuple[str, str]]) -> str:
    return f"[{name}]\n" + "".join(f"{k}={v}\n" for k, v in keys) + "\n"


def _var(name: str, title: str, datatype: str, access: str, default: str, *,
         pdo: str = "0") -> str:
    return _section(name, [("ParameterName", title), ("ObjectType", "0x7"),
                           ("DataType", datatype), ("AccessType", access),
                           ("DefaultValue", default), ("PDOMapping", pdo)])


def _head(name: str, title: str, object_type: str, subs: int) -> str:
    return _section(name, [("ParameterName", title), ("ObjectType", object_type),
                           ("SubNumber", hex(subs))])


def _array(index: str, title: str, item: str, datatype: str, access: str, *, count: int,
           default: str, pdo: str = "0") -> str:
    """An ARRAY of ``count`` equal entries after its sub-index 0."""
    text = _head(index, title, "0x8", count + 1)
    text += _var(f"{index}sub0", "Highest sub-index supported", U8, "ro", f"0x{count:02X}")
    for sub in range(1, count + 1):
        text += _var(f"{index}sub{sub:X}", item, datatype, access, default, pdo=pdo)
    return text


def _file(name: str, info: str, objects: dict[int, str], mandatory: tuple[int, ...],
          manufacturer: tuple[int, ...] = ()) -> str:
    """The EDS text: its header (``info``: [DeviceInfo]'s lines of the tester's interest),
    the three object lists and the objects' sections."""
    text = (f"[FileInfo]\nFileName={name}\nEDSVersion=4.0\n\n[DeviceInfo]\n{info}\n"
            "NrOfRXPDO=4\nNrOfTXPDO=4\nLSS_Supported=1\n\n")
    optional = [i for i in objects if i not in mandatory and i not in manufacturer]
    for title, indices in (("MandatoryObjects", mandatory), ("OptionalObjects", optional),
                           ("ManufacturerObjects", manufacturer)):
        if indices:
            text += (f"[{title}]\nSupportedObjects={len(indices)}\n"
                     + "".join(f"{n}=0x{i:04X}\n" for n, i in enumerate(indices, 1)) + "\n")
    return text + "".join(objects[i] for i in sorted(objects))


def _identity(defaults: tuple[int, int, int, int]) -> str:
    text = _head("1018", "Identity", "0x9", 5)
    text += _var("1018sub0", "Highest sub-index supported", U8, "ro", "0x04")
    for sub, (title, value) in enumerate(zip(("Vendor-ID", "Product code", "Revision number",
                                              "Serial number"), defaults, strict=True), 1):
        text += _var(f"1018sub{sub}", title, U32, "ro", f"0x{value:08X}")
    return text


def _store_restore(save: tuple[str, ...], save_defaults: tuple[int, ...],
                   restore: tuple[str, ...]) -> dict[int, str]:
    """0x1010 and 0x1011 with their sub-indices' names (0x1011's defaults are all 1)."""
    found = {}
    for index, what, names, defaults in (
            (0x1010, "Store parameters", save, save_defaults),
            (0x1011, "Restore default parameters", restore, (1,) * len(restore))):
        name = f"{index:04X}"
        text = _head(name, what, "0x8", len(names) + 1)
        text += _var(f"{name}sub0", "Highest sub-index supported", U8, "ro",
                     f"0x{len(names):02X}")
        for sub, (title, value) in enumerate(zip(names, defaults, strict=True), 1):
            text += _var(f"{name}sub{sub}", title, U32, "rw", f"0x{value:08X}")
        found[index] = text
    return found


def _communication() -> dict[int, str]:
    """The communication objects both devices share: 0x1000/0x1001 aside, 0x1003, SYNC,
    TIME, EMCY, heartbeat and the SDO server."""
    found = {0x1003: _head("1003", "Pre-defined error field", "0x8", 0x11)
             + _var("1003sub0", "Number of errors", U8, "rw", "")
             + "".join(_var(f"1003sub{sub:X}", "Standard error field", U32, "ro", "")
                       for sub in range(1, 17))}
    found[0x1005] = _var("1005", "COB-ID SYNC message", U32, "rw", "0x00000080")
    found[0x1006] = _var("1006", "Communication cycle period", U32, "rw", "0")
    found[0x1007] = _var("1007", "Synchronous window length", U32, "rw", "0")
    found[0x1012] = _var("1012", "COB-ID time stamp object", U32, "rw", "0x00000100")
    found[0x1014] = _var("1014", "COB-ID EMCY", U32, "rw", "0x80+$NODEID")
    found[0x1015] = _var("1015", "Inhibit time EMCY", U16, "rw", "0")
    found[0x1016] = _head("1016", "Consumer heartbeat time", "0x8", 9) + "".join(
        [_var("1016sub0", "Highest sub-index supported", U8, "ro", "0x08")]
        + [_var(f"1016sub{sub}", "Consumer heartbeat time", U32, "rw", "0x00000000")
           for sub in range(1, 9)])
    found[0x1017] = _var("1017", "Producer heartbeat time", U16, "rw", "0")
    found[0x1019] = _var("1019", "Synchronous counter overflow value", U8, "rw", "0")
    found[0x1200] = (_head("1200", "SDO server parameter", "0x9", 3)
                     + _var("1200sub0", "Highest sub-index supported", U8, "ro", "2")
                     + _var("1200sub1", "COB-ID client to server (rx)", U32, "ro",
                            "0x600+$NODEID", pdo="1")
                     + _var("1200sub2", "COB-ID server to client (tx)", U32, "ro",
                            "0x580+$NODEID", pdo="1"))
    return found


def _pdos(cob_ids: tuple[int, ...], types: tuple[int, ...],
          mappings: dict[int, tuple[int, list[int]]]) -> dict[int, str]:
    """RPDO1..4 and TPDO1..4: their COB-IDs (before $NODEID, RPDOs first) and transmission
    types; the mappings not all zero as (number of entries, the entries' defaults)."""
    found = {}
    for n in range(8):
        tpdo = n >= 4
        comm, kind = (0x1800 if tpdo else 0x1400) + n % 4, "TPDO" if tpdo else "RPDO"
        name = f"{comm:04X}"
        text = _head(name, f"{kind} communication parameter", "0x9", 6 if tpdo else 4)
        text += _var(f"{name}sub0", "Highest sub-index supported", U8, "ro",
                     "0x06" if tpdo else "0x05")
        text += _var(f"{name}sub1", f"COB-ID used by {kind}", U32, "rw",
                     f"0x{cob_ids[n]:08X}+$NODEID")
        text += _var(f"{name}sub2", "Transmission type", U8, "rw", str(types[n]))
        if tpdo:
            text += _var(f"{name}sub3", "Inhibit time", U16, "rw", "0")
        text += _var(f"{name}sub5", "Event timer", U16, "rw", "0")
        if tpdo:
            text += _var(f"{name}sub6", "SYNC start value", U8, "rw", "0")
        found[comm] = text
        mapping = comm + 0x200
        count, objects = mappings.get(mapping, (0, []))
        text = _head(f"{mapping:04X}", f"{kind} mapping parameter", "0x9", 9)
        text += _var(f"{mapping:04X}sub0", "Number of mapped application objects in PDO",
                     U8, "rw", str(count))
        for k in range(1, 9):
            value = objects[k - 1] if k <= len(objects) else 0
            text += _var(f"{mapping:04X}sub{k}", f"Application object {k}", U32, "rw",
                         f"0x{value:08X}")
        found[mapping] = text
    return found


def canopend_eds() -> str:
    """The EDS text of canopend's dictionary (no manufacturer objects; 0x1003 of 16)."""
    objects = {0x1000: _var("1000", "Device type", U32, "ro", "0x00000000"),
               0x1001: _var("1001", "Error register", U8, "ro", "0x00", pdo="1"),
               0x1018: _identity((0, 0, 0, 0))}
    objects.update(_communication())
    groups = ("all", "communication", "application", "manufacturer defined")
    objects.update(_store_restore(tuple(f"Save {g} parameters" for g in groups), (1,) * 4,
                                  tuple(f"Restore {g} parameters" for g in groups)))
    objects[0x1280] = (_head("1280", "SDO client parameter", "0x9", 4)
                       + _var("1280sub0", "Highest sub-index supported", U8, "ro", "0x03")
                       + _var("1280sub1", "COB-ID client to server (tx)", U32, "rw",
                              "0x80000000", pdo="1")
                       + _var("1280sub2", "COB-ID server to client (rx)", U32, "rw",
                              "0x80000000", pdo="1")
                       + _var("1280sub3", "Node-ID of the SDO server", U8, "rw", "0x01"))
    objects.update(_pdos((0x80000200, 0x80000300, 0x80000400, 0x80000500,
                          0xC0000180, 0xC0000280, 0xC0000380, 0xC0000480), (254,) * 8, {}))
    return _file("DS301_profile.eds", "ProductName=New Product", objects,
                 (0x1000, 0x1001, 0x1018))


#: 0x2121:2's default, as demoDevice.eds gives it (a tab and a euro sign in it).
LONG_STRING = ("Example string with 1000 bytes capacity. It may contain UTF-8 characters, "
               "like '\u20ac', tabs '\t', newlines, etc.")


def demodevice_eds() -> str:
    """The EDS text of CANopenDemo's demoDevice (0x2122 a DOMAIN; 0x2121:1 a 3-byte string)."""
    objects = {0x1000: _var("1000", "Device type", U32, "ro", "0x000F0191"),
               0x1001: _var("1001", "Error register", U8, "ro", "0x00", pdo="1"),
               0x1018: _identity((0, 1, 0, 3))}
    objects.update(_communication())
    for index, title in ((0x1008, "Manufacturer device name"),
                         (0x1009, "Manufacturer hardware version"),
                         (0x100A, "Manufacturer software version")):
        objects[index] = _var(f"{index:04X}", title, VSTRING, "ro", "")
    objects.update(_store_restore(
        ("Save all parameters", "Save communication parameters",
         "Save application parameters", "Save mainline data block",
         "Save PERSIST_APP parameters", "Save PERSIST_APP_AUTO auto-store parameters"),
        (3, 1, 1, 3, 1, 3),
        ("Restore all default parameters", "Restore communication default parameters",
         "Restore application default parameters", "Restore mainline default data block",
         "Restore PERSIST_APP default parameters",
         "Restore PERSIST_APP_AUTO auto-store default parameters")))
    objects.update(_pdos((0x200, 0x300, 0x80000400, 0x80000500,
                          0x40000180, 0x40000280, 0xC0000380, 0xC0000480),
                         (255, 255, 254, 254, 255, 255, 254, 254),
                         {0x1600: (2, [0x62000108 + (k << 8) for k in range(8)]),
                          0x1601: (4, [0x64110110 + (k << 8) for k in range(4)]),
                          0x1A00: (2, [0x60000108 + (k << 8) for k in range(8)]),
                          0x1A01: (4, [0x64010110 + (k << 8) for k in range(4)])}))
    for index, title, item, datatype, access, count, default in (
            (0x6000, "Read digital input 8-bit", "Input", U8, "ro", 8, "0x00"),
            (0x6200, "Write digital output 8-bit", "Output", U8, "rw", 8, "0x00"),
            (0x6401, "Read analog input 16-bit", "Input", I16, "ro", 16, "0"),
            (0x6411, "Write analog output 16-bit", "Output", I16, "rw", 8, "0")):
        objects[index] = _array(f"{index:04X}", title, item, datatype, access, count=count,
                                default=default, pdo="1")
    manufacturer = (0x2100, 0x2106, 0x2110, 0x2111, 0x2112, 0x2120, 0x2121, 0x2122)
    objects[0x2100] = _var("2100", "Error status bits", OSTRING, "ro", "00" * 10, pdo="1")
    objects[0x2106] = _var("2106", "Power-on counter", U32, "ro", "0")
    for index, title, pdo in ((0x2110, "Variable Int32", "1"),
                              (0x2111, "Variable Int32 save", "0"),
                              (0x2112, "Variable NV Int32 auto save", "0")):
        objects[index] = _array(f"{index:04X}", title, "int32", I32, "rw", count=16,
                                default="0", pdo=pdo)
    objects[0x2120] = (_head("2120", "Demo record", "0x9", 7)
                       + _var("2120sub0", "Highest sub-index supported", U8, "ro", "0x06")
                       + _var("2120sub1", "I64", I64, "rw", "-1234567890123456789", pdo="1")
                       + _var("2120sub2", "U64", U64, "rw", "0x1234567890ABCDEF", pdo="1")
                       + _var("2120sub3", "R32", R32, "rw", "12.345", pdo="1")
                       + _var("2120sub4", "R64", R64, "rw", "456.789", pdo="1")
                       + _var("2120sub5", "Average of four numbers", R64, "ro", "", pdo="1")
                       + _var("2120sub6", "Parameter with default value", U16, "rw",
                              "0x1234"))
    objects[0x2121] = (_head("2121", "Demo strings", "0x9", 4)
                       + _var("2121sub0", "Highest sub-index supported", U8, "ro", "0x03")
                       + _var("2121sub1", "String short", VSTRING, "rw", "str")
                       + _var("2121sub2", "String long", VSTRING, "rw", LONG_STRING)
                       + _var("2121sub3", "Octet string", OSTRING, "rw", "C83DBB"))
    objects[0x2122] = _var("2122", "Demo domain", DOMAIN, "rw", "")
    return _file("demoDevice.eds", "VendorNumber=0\nProductName=Demo device\nProductNumber=1\n"
                 "RevisionNumber=0", objects, (0x1000, 0x1001, 0x1018), manufacturer)


#: The EDS text of each recorded device, by its trace's name.
EDS = {"canopend": canopend_eds, "demodevice": demodevice_eds}
