# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
"""sss_farm: the code of sss-farm (docs/farm.md), which submits the sss chain
(ptbake -> ptfilter -> brickmake -> render) over a list of frames to Slurm,
one job array per stage, and reports on it. Python 3 standard library only.

The script src/farm/sss-farm finds this package (the build and the install
put it in share/sss/farm/ beside bin/) and calls cli.main. By concern:

  common   the program's name and version, defaults, errors, message lines
  frames   --frames lists and frame patterns (the tools' rules)
  spec     DIR/.sss-farm/NAME.json: paths, reading and checking, writing
  stages   what a stage reads and writes, and the tool command it runs
  slurm    squeue, scontrol and sacct: the state of a submission's tasks
  submit   the `submit` command
  task     the `task` command (what each array task runs)
  status   the `status` command
  cli      the command line, the help, and main()
"""
