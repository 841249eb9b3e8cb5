"""From records to true stress-strain curves, hardening, friction and Johnson-Cook constants."""
