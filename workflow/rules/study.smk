# The simulated study, learning and the expert case study (issue 4) go here.
#
# Not wired yet: `casa simulate` and `casa case-study` do not exist at the time of
# writing (`casa learn` does). When they land:
#   1. write the rules below, per participant so that --cores 2 keeps both cores
#      busy, with simulation and learning as separate jobs;
#   2. set SIMULATE = True and CASE_STUDY = True in common.smk.
# The rest of the DAG is already written against their outputs:
#   - data/raw/simulated/.complete marks a finished simulated study; the folder
#     then holds casa-trial/1 logs and surveys.csv files (one per participant is
#     fine), like any dataset, and is checked, processed, analysed and drawn as one;
#   - data/processed/case_study/steps.csv and .../arbitration.csv feed the rules
#     figure_case_study and figure_arbitration (workflow/rules/figures.smk).
#
# A sketch; the options of `casa simulate` and `casa case-study` are still to be
# settled with their authors:
#
# PARTICIPANTS = [f"p{i:02d}" for i in range(1, config["simulation"]["participants"] + 1)]
#
# rule simulate_before_learning:   # familiarization, NA/PBA/CASA, the demonstrations
#     output: directory(RAW / "simulated" / "{participant}" / "before")
#     params: seed=config["simulation"]["seed"]
#     log: "logs/simulate/{participant}_before.log"
#     conda: "../envs/casa.yaml"
#     shell: "casa simulate --participant {wildcards.participant} --seed {params.seed} ..."
#
# rule learn:                      # one job per participant and unknown task
#     input: RAW / "simulated" / "{participant}" / "before"
#     output: directory("data/interim/simulated/{participant}/library/{task}")
#     log: "logs/learn/{participant}_{task}.log"
#     conda: "../envs/casa.yaml"
#     shell: "casa learn --demos {input} --task {wildcards.task} --name {wildcards.task} "
#            "--library {output} --participant {wildcards.participant} > {log} 2>&1"
#
# rule simulate_after_learning:    # CASA after learning, with the learned intents
#     input: ...the participant's libraries...
#     output: directory(RAW / "simulated" / "{participant}" / "after")
#     ...
#
# rule simulated_study:            # the marker the dataset rules wait for
#     input: expand(RAW / "simulated" / "{participant}" / "after", participant=PARTICIPANTS)
#     output: touch(RAW / "simulated" / ".complete")
#     log: "logs/simulate/complete.log"
#
# rule case_study:
#     output:
#         steps=PROCESSED / "case_study" / "steps.csv",
#         arbitration=PROCESSED / "case_study" / "arbitration.csv",
#     log: "logs/case_study.log"
#     conda: "../envs/casa.yaml"
#     shell: "casa case-study --scene {input.scene} ... > {log} 2>&1"
