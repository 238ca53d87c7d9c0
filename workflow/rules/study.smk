# The simulated study (paper, Sec. V), learning, and the expert case study (Sec. IV).
# Per participant: simulation before learning, learning of each unknown task and
# simulation after learning are separate jobs, so that --cores 2 keeps both busy.
# The simulated study is the dataset data/raw/simulated; .complete marks it done.

PARTICIPANTS = list(range(1, config["simulation"]["participants"] + 1))
SIMULATED = RAW / "simulated"
INTENTS = PROCESSED / "simulated" / "intents"


wildcard_constraints:
    p=r"\d+",
    task="|".join(UNKNOWN_TASKS),


rule simulate_before_learning:
    input:
        config=CONFIG_FILE,
        scene=config["scene"],
    output:
        directory(SIMULATED / "p{p}" / "before"),
    log:
        "logs/simulate/p{p}_before.log",
    conda:
        "../envs/casa.yaml"
    shell:
        "exec casa simulate before --config {input.config} --participant {wildcards.p} "
        "--out {output} > {log} 2>&1"


rule learn_intent:
    input:
        before=SIMULATED / "p{p}" / "before",
        config=CONFIG_FILE,
    output:
        library=directory(INTENTS / "p{p}" / "{task}"),
        row=PROCESSED / "simulated" / "learning" / "p{p}_{task}.csv",
        timing=PROCESSED / "simulated" / "learning" / "p{p}_{task}_timing.csv",
    log:
        "logs/learn/p{p}_{task}.log",
    conda:
        "../envs/casa.yaml"
    shell:
        "exec casa simulate learn --config {input.config} --participant {wildcards.p} "
        "--task {wildcards.task} --before {input.before} --library {output.library} "
        "--out {output.row} --timing {output.timing} > {log} 2>&1"


rule simulate_after_learning:
    input:
        before=SIMULATED / "p{p}" / "before",
        config=CONFIG_FILE,
        libraries=expand(INTENTS / "p{{p}}" / "{task}", task=UNKNOWN_TASKS),
    output:
        directory(SIMULATED / "p{p}" / "after"),
    log:
        "logs/simulate/p{p}_after.log",
    conda:
        "../envs/casa.yaml"
    params:
        library=lambda wildcards: INTENTS / f"p{wildcards.p}",
    shell:
        "exec casa simulate after --config {input.config} --participant {wildcards.p} "
        "--before {input.before} --library {params.library} --out {output} > {log} 2>&1"


rule learning_table:
    input:
        rows=expand(
            PROCESSED / "simulated" / "learning" / "p{p}_{task}.csv",
            p=PARTICIPANTS,
            task=UNKNOWN_TASKS,
        ),
        timing=expand(
            PROCESSED / "simulated" / "learning" / "p{p}_{task}_timing.csv",
            p=PARTICIPANTS,
            task=UNKNOWN_TASKS,
        ),
    output:
        table=PROCESSED / "simulated" / "learning.csv",
        timing=PROCESSED / "simulated" / "learning_timing.csv",
    log:
        "logs/simulate/learning_table.log",
    conda:
        "../envs/casa.yaml"
    shell:
        "exec casa simulate learning-table --rows {input.rows} --out {output.table} "
        "--timing-rows {input.timing} --timing {output.timing} > {log} 2>&1"


rule simulated_study:
    input:
        expand(SIMULATED / "p{p}" / "after", p=PARTICIPANTS),
        PROCESSED / "simulated" / "learning.csv",
    output:
        touch(SIMULATED / ".complete"),
    log:
        "logs/simulate/complete.log",


rule case_study:
    input:
        config=CONFIG_FILE,
        scene=config["scene"],
    output:
        steps=PROCESSED / "case_study" / "steps.csv",
        arbitration=PROCESSED / "case_study" / "arbitration.csv",
        work=directory("data/interim/case_study"),
    log:
        "logs/case_study.log",
    conda:
        "../envs/casa.yaml"
    shell:
        "exec casa case-study --config {input.config} --work {output.work} "
        "--steps {output.steps} --arbitration {output.arbitration} > {log} 2>&1"
