"""Input-output models: instruments, the modal plant, the volts-volts block diagram, their parameters."""

#: Highest retained mode [Hz] of the models (thesis 3.4: modes to 250 Hz); also the modes a deck without
#: an EIGRL range gets.
DEFAULT_MAX_HZ = 250.0
