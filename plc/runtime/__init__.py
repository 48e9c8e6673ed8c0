"""Embedded soft-PLC runtime: OpenPLC v3's Modbus TCP map over a compiled ST `Application`.

Modules: `codec` (values <-> 16-bit words), `addressmap` (OpenPLC table layout),
`image` (located memory as Modbus tables), `control` (soft-PLC control block),
`engine` (scan loop, stepping, faults), `datastore` + `server` (pymodbus server),
`rawclient` (minimal Modbus TCP client), `cli` (`thermost plc`).
"""
