"""What every node needs to run: main() and spinning (``spin``), callbacks that never
raise (``guard``), slow work off the executor (``rebuild``), /diagnostics statuses
(``diagnostics``), publishers that know their subscribers (``listened``)."""
