"""What every node needs to run: main() and spinning (``spin``, ``command_line``), callbacks
that never raise (``guard``), slow work off the executor (``rebuild``), /diagnostics
(``diagnostics``), publishers that know their subscribers (``listened``)."""
