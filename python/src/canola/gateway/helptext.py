# SPDX-License-Identifier: Apache-2.0
"""The texts of ``help``, ``help datatype`` and ``help lss``.

Each is one reply of several lines: the executor joins them with LF and the server ends
the reply with one CR LF, as CANopenNode's gateway does (``cocomm`` reads a reply up to
the first CR LF).
"""

from __future__ import annotations

__all__ = ["HELP", "HELP_DATATYPE", "HELP_LSS", "TOPICS"]

HELP = """\
canola CiA 309-3 gateway. Requests: [<seq>] [[<net>] <node>] <command>; replies
[<seq>] OK | <value> | ERROR:0x<SDO abort code> | ERROR:<gateway error code>.
  r[ead] <index> <sub> [<type>]           SDO upload (no type: hex bytes)
  w[rite] <index> <sub> <type> <value>    SDO download
  start | stop | preop[erational]         NMT (to the gateway's own node-ID or to all:
  reset node | reset comm[unication]      sent on the bus and applied to it too; while
                                          it is stopped, SDO answers ERROR:204)
  enable heartbeat <ms> | disable heartbeat   watch a node's heartbeat
  [<net>] set network|node <n>            defaults of this connection (net 0: this one)
  [<net>] set sdo_timeout <ms>            SDO time-out per answer (default: --sdo-timeout)
  [<net>] set sdo_block 0|1               SDO block transfer
  [<net>] set heartbeat <ms>              the gateway's own heartbeat
  [<net>] set events 0|1                  all events to this connection
  [<net>] boot_up_indication Enable|Disable
  [<net>] set rpdo|tpdo[x] ... | r[ead] p[do] <n> | w[rite] p[do] <n> <count> <values>
  info version | help [datatype|lss]
  auth <token>                            the first line, where the gateway asks for one
Events (without sequence number): <net> <node> BOOT_UP | <net> <node> ERROR 203
  (heartbeat lost) | <net> <node> ERROR 202 | <net> <node> EMCY <code> <reg> <5 bytes>
  | <net> pdo <num> <count> <values> (the gateway's RPDO received)
'#' starts a comment; an empty or comment-only line gets an empty reply."""

HELP_DATATYPE = """\
b boolean; i8 i16 i24 i32 i40 i48 i56 i64 signed; u8 .. u64 unsigned;
x8 .. x64 unsigned shown in hex; r32 r64 real; t td time of day / difference
as '<ms> <days>'; vs visible string ("quoted", "" for a quote, escapes \\\\ \\n \\r
\\t \\xHH); os us d octet string, unicode string, domain as base64; hex raw bytes as
hex pairs."""

HELP_LSS = """\
LSS (CiA 305) through the gateway's LSS master; all start with [<seq>] [<net>]:
  lss_switch_glob 0|1                     switch state global (0 waiting, 1 configuration)
  lss_switch_sel <vendor> <product> <revision> <serial>   switch state selective
  lss_set_node <node>                     configure node-ID (1..127, 255: none)
  lss_store                               store configuration
  lss_inquire_addr [0..3]                 inquire vendor, product, revision, serial (all 4)
  lss_get_node                            inquire node-ID
  _lss_fastscan [<timeout ms>]            fastscan one device without node-ID: its address
                                          (it stays in configuration; 0 ms: 100 ms)
  lss_allnodes [<timeout ms> [<first node> <store 0|1> [0 <v> 0 <p> 0 <r> 0 <s>]]]
                                          give every device without node-ID the next one
  lss_conf_bitrate, lss_activate_bitrate, lss_identity, lss_ident_nonconf: ERROR:100
Errors: 101 arguments, 102 no device in configuration (or not all waiting, for a scan),
103 no answer, 501 refused (manufacturer), 502 node-ID refused, 504 store refused."""

#: ``help <topic>`` -> its text ("" is plain ``help``).
TOPICS = {"": HELP, "datatype": HELP_DATATYPE, "lss": HELP_LSS}
