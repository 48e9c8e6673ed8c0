"""pymodbus datastore backed by the located memory image and the control block.

Every request takes the engine lock, so it runs between two scans (OpenPLC locks its
buffers the same way). Any unit id is answered with the same device.
"""

from __future__ import annotations

from collections.abc import Sequence

from pymodbus.constants import ExcCodes
from pymodbus.datastore import ModbusServerContext

from plc.runtime import control
from plc.runtime.addressmap import ModbusError, Table
from plc.runtime.engine import PlcEngine
from plc.runtime.image import ModbusImage

READ_WRITE_FUNCTION = 23  # FC23: write, then read (RW_STEPS scans run in between)

FUNCTION_TABLES: dict[int, Table] = {
    1: Table.COIL,
    5: Table.COIL,
    15: Table.COIL,
    2: Table.DISCRETE_INPUT,
    3: Table.HOLDING,
    6: Table.HOLDING,
    16: Table.HOLDING,
    22: Table.HOLDING,
    23: Table.HOLDING,
    4: Table.INPUT_REGISTER,
}


class PlcDatastore(ModbusServerContext):
    """The server context pymodbus calls for every read and write.

    It subclasses `ModbusServerContext` only so the server accepts it; none of the base
    class' state is used (its constructor would build an unused simulator device).
    """

    def __init__(self, image: ModbusImage, engine: PlcEngine):  # noqa: D107 - base init skipped on purpose
        self.image = image
        self.engine = engine
        self.old_simulator = True  # the server then calls our async_getValues/async_setValues
        self.simdevices = []

    def device_ids(self) -> list[int]:
        return [0]

    def read(self, func_code: int, address: int, count: int) -> list[int] | list[bool] | ModbusError:
        table = FUNCTION_TABLES.get(func_code)
        if table is None:
            return ModbusError.ILLEGAL_FUNCTION
        with self.engine.lock:
            if table is Table.HOLDING and address >= control.CONTROL_BASE:
                return self.engine.read_control(address, count)
            if table in (Table.COIL, Table.DISCRETE_INPUT):
                return self.image.read_bits(table, address, count)
            return self.image.read_registers(table, address, count)

    def write(
        self, func_code: int, address: int, values: Sequence[int] | Sequence[bool]
    ) -> ModbusError | None:
        table = FUNCTION_TABLES.get(func_code)
        if table is None:
            return ModbusError.ILLEGAL_FUNCTION
        with self.engine.lock:
            if table is Table.HOLDING and address >= control.CONTROL_BASE:
                return self.engine.write_control(address, [int(v) for v in values])
            if table is Table.COIL:
                return self.image.write_bits(table, address, [bool(v) for v in values])
            result = self.image.write_registers(table, address, [int(v) for v in values])
            if result is None and func_code == READ_WRITE_FUNCTION and self.engine.rw_steps:
                return None if self.engine.step(self.engine.rw_steps) else ModbusError.DEVICE_FAILURE
            return result

    async def async_getValues(  # noqa: N802 - pymodbus API name
        self, device_id: int, func_code: int, address: int, count: int = 1
    ) -> list[int] | list[bool] | ExcCodes:
        result = self.read(func_code, address, count)
        return ExcCodes(int(result)) if isinstance(result, ModbusError) else result

    async def async_setValues(  # noqa: N802 - pymodbus API name
        self, device_id: int, func_code: int, address: int, values: Sequence[int] | Sequence[bool]
    ) -> ExcCodes | None:
        result = self.write(func_code, address, values)
        return None if result is None else ExcCodes(int(result))
